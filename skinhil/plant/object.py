"""The held object on the board: the grip the hand holds, the lift running, slip and drop.

Per tick the board calls :meth:`HeldObject.before_tick` (the grip set-point onto every lift's
contact that has not dropped, 0 N on a dropped one) and, after the model's steps,
:meth:`HeldObject.after_tick` with the contacts' per-step truth: the running lift's slip
distance grows by ``Σ v_slip·dt`` over the steps in gross slip (every touching mass slipping;
``v_slip`` the contact's slip speed), and once it passes ``drop_distance_m`` the object drops
(its grip goes to 0 N: the hand no longer holds it); it drops too when, loaded, it touches
no mass of the skin at some step (it has left the skin's patch). An object of a drawn run
(:class:`skinhil.plant.lifts.LiftScene`) breaks once its lift runs, not dropped, under a grip
above its break force: the lift fails, whatever follows. A GRIP
(:meth:`HeldObject.set_grip`) changes the grip from the next tick on, within the bounds of
:class:`GraspParams`.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from skinhil.plant.lifts import GraspParams, Lift, LiftScene
from skinhil.plant.truth import HELD_DTYPE
from skinhil.world import World
from skinhil.world.truth import T_FX, T_FY, T_NODES, T_NORMAL, T_SLIP, T_SLIP_SPEED

GROSS = 3
"""The contact's slip code of gross slip (every touching mass slips)."""
GRIP_OUTCOMES = ("ok", "bad_argument", "above_max", "too_fast")
"""What :meth:`HeldObject.set_grip` says: accepted; not a finite number >= 0; above
``max_grip_n``; faster than ``max_rate_n_per_s``."""


@dataclass(frozen=True)
class GripEntry:
    """One accepted GRIP: its token, arrival and execution board times (µs), the grip (N)."""

    token: int
    arrival_us: int
    applied_us: int
    grip_n: float


class HeldObject:
    """The object of ``params`` lifted through ``world``'s contacts (one per lift, scene
    time ``i·period_s``); ``tick_us`` is the board's tick (µs), the shortest time a rate is
    taken over."""

    def __init__(self, params: GraspParams, world: World, tick_us: int) -> None:
        self.params = params
        self.world = world
        self.tick_us = int(tick_us)
        self.loads = params.load_keyframes()
        scene = world.scene
        self.lifts: tuple[Lift, ...] | None = (
            scene.lifts if isinstance(scene, LiftScene) else None)
        """The drawn run's lifts (None: every lift the object of ``params``, one every
        ``period_s``)."""
        n = len(scene.contacts)
        self._loads = ([params.load_keyframes(lift) for lift in self.lifts] if self.lifts
                       else [self.loads] * n)
        self._starts = [c.start_s for c in scene.contacts]
        self._durations = ([params.lift_duration_s(lift) for lift in self.lifts] if self.lifts
                           else [params.lift_s] * n)
        self.break_n = np.array([lift.break_n for lift in self.lifts] if self.lifts
                                else [math.inf] * n)
        """Each lift's break force (N)."""
        self.broken = np.zeros(n, dtype=bool)
        """Whether each lift's object has broken."""
        self.grip_n = params.initial_grip_n
        self._last_us = 0
        self.slid_m = np.zeros(n)
        """How far each lift's object has slid (m)."""
        self.dropped = np.zeros(n, dtype=bool)
        self.log: list[GripEntry] = []
        """Every accepted GRIP, in order (the board's grip log)."""
        self.refused = {k: 0 for k in GRIP_OUTCOMES[1:]}
        """GRIPs refused, by outcome."""

    def reset(self) -> None:
        """Back to the hand's initial grip, no lift slid or dropped (the scene restarts)."""
        self.grip_n = self.params.initial_grip_n
        self._last_us = 0
        self.slid_m[:] = 0.0
        self.dropped[:] = False
        self.broken[:] = False

    def set_grip(self, grip_n: float, now_us: int, arrival_us: int | None = None,
                 token: int = 0) -> str:
        """Set the grip (N) at board time ``now_us`` (µs), from the next tick on; the outcome
        (:data:`GRIP_OUTCOMES`). A grip must be finite, 0..``max_grip_n``, and differ from
        the present one by at most ``max_rate_n_per_s`` times the time since the last
        accepted GRIP (at least one tick)."""
        p = self.params
        if not (math.isfinite(grip_n) and grip_n >= 0):
            outcome = "bad_argument"
        elif grip_n > p.max_grip_n:
            outcome = "above_max"
        elif abs(grip_n - self.grip_n) > p.max_rate_n_per_s * 1e-6 * max(
                now_us - self._last_us, self.tick_us) * (1 + 1e-9):
            outcome = "too_fast"
        else:
            self.grip_n = float(grip_n)
            self._last_us = int(now_us)
            self.log.append(GripEntry(token, int(now_us if arrival_us is None else arrival_us),
                                      int(now_us), self.grip_n))
            return "ok"
        self.refused[outcome] += 1
        return outcome

    def before_tick(self) -> None:
        """The grip onto every lift's contact (0 N on a dropped object's)."""
        setpoint = self.world.state.setpoint
        setpoint[:] = np.where(self.dropped, 0.0, self.grip_n)

    def lift_at(self, scene_s: float) -> int:
        """The lift running at scene time ``scene_s`` (s): its index, or -1."""
        p = self.params
        if self.lifts is not None:
            i = bisect.bisect_right(self._starts, scene_s) - 1
            if i < 0 or scene_s - self._starts[i] > self._durations[i]:
                return -1
            return i
        i = int(math.floor(scene_s / p.period_s)) if scene_s >= 0 else -1
        if not 0 <= i < len(self.dropped) or scene_s - i * p.period_s > p.lift_s:
            return -1
        return i

    def after_tick(self, t_us: int, scene_s: float, dt_s: float, raw: np.ndarray) -> np.ndarray:
        """Account a tick whose first step was at board time ``t_us`` (µs) and scene time
        ``scene_s`` (s), of steps ``dt_s`` (s) with the contacts' per-step truth ``raw``
        (n_steps, n_contacts, RAW_FIELDS): its record (:data:`HELD_DTYPE`, one row)."""
        row = np.zeros(1, dtype=HELD_DTYPE)
        row["t_us"] = t_us
        row["grip_n"] = self.grip_n
        i = self.lift_at(scene_s)
        if i < 0:
            return row
        r = raw[:, i]
        tau = scene_s - (i * self.params.period_s if self.lifts is None else self._starts[i])
        loads = self._loads[i]
        load = float(np.interp(tau, loads[:, 0], loads[:, 1]))
        gross = r[:, T_SLIP] == GROSS
        if not self.dropped[i]:
            self.slid_m[i] += float(r[gross, T_SLIP_SPEED].sum()) * dt_s
            if self.slid_m[i] > self.params.drop_distance_m or (
                    load > 0 and (r[:, T_NODES] == 0).any()):
                self.dropped[i] = True  # slid too far, or off the skin under its load
            if self.grip_n > self.break_n[i]:
                self.broken[i] = True
        row["lift"] = i + 1
        row["dropped"] = self.dropped[i]
        row["held"] = not (self.dropped[i] or self.broken[i])
        row["broken"] = self.broken[i]
        row["load_n"] = load
        row["normal_n"] = r[0, T_NORMAL]
        row["tangential_n"] = math.hypot(r[0, T_FX], r[0, T_FY])
        row["slip"] = r[0, T_SLIP]
        row["slip_distance_mm"] = self.slid_m[i] * 1e3
        return row
