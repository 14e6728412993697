"""A run of lifts as a scene: the object's parameters, its load profile, one contact per lift.

Each lift is one contact (:class:`skinhil.world.Contact`) of a flat pad, the object's face,
under force control on both axes: the normal load is the grip (set at run time,
:meth:`skinhil.world.World.set_load`), the tangential load along x is the object's load
``L(t)`` (N), a table of keyframes:

    0 .. grasp_s                 L = 0                     the hand closes at its grip
    .. + rise_s                  L rises to m·g            the lift
    .. + hold_s                  L = m·g, with a pull of pull_n (ramps of ramp_s) in its middle
    .. + lower_s                 L falls to 0              the object is set down
    .. + settle_s                L = 0, then the contact ends (the hand opens)

followed by ``gap_s`` with nothing touching before the next lift.

A drawn run (:func:`drawn_lift_scene`) gives each lift its own :class:`Lift`: its start, its
grasp time, its object's mass and break force, its pull's size and place in the hold; the
scene it makes (:class:`LiftScene`) carries them to the held object.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Real
from typing import ClassVar

import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import Constraints, Interval, non_negative, positive, validate_params
from skinhil.world import Contact, Indenter, Scene, Trajectory
from skinhil.world.scene import MAX_CONTACTS

G_M_PER_S2 = 9.81
"""Standard gravity (m/s²)."""


@dataclass(frozen=True)
class GraspParams:
    """The held object, its lifts and the grip's bounds (SI units; docs/grasp.md)."""

    mass_kg: float = 0.05
    """The object's mass: its load at hold is m·g (0.49 N)."""
    pull_n: float = 0.15
    """The perturbation: an extra pull (N) in the middle of the hold."""
    pad_radius_m: float = 1.2e-3
    """The object's face: a flat pad of this radius (covers five masses of a 1 mm skin)."""
    mu_static: float = 0.8
    mu_kinetic: float = 0.6
    """Friction between the object and the skin: slip ratio grip/load = 1/mu_static."""
    initial_grip_n: float = 0.3
    """The grip (N) before any GRIP command: the hand's low grip (half what the weight
    needs: m·g/mu_static = 0.61 N)."""
    max_grip_n: float = 2.0
    """The largest grip (N) a GRIP may set."""
    max_rate_n_per_s: float = 100.0
    """The fastest grip change (N/s) a GRIP may ask, from the last accepted one."""
    drop_distance_m: float = 1e-3
    """The object drops once it has slid this far (m) on the skin in one lift."""
    grasp_s: float = 0.15
    rise_s: float = 0.2
    hold_s: float = 0.45
    pull_s: float = 0.1
    ramp_s: float = 0.02
    lower_s: float = 0.2
    settle_s: float = 0.05
    gap_s: float = 0.1

    _parameter_constraints: ClassVar[Constraints] = {
        "mass_kg": non_negative("kg"),
        "pull_n": non_negative("N"),
        "pad_radius_m": non_negative("m"),
        "mu_static": positive("friction coefficient"),
        "mu_kinetic": positive("friction coefficient"),
        "initial_grip_n": positive("N"),
        "max_grip_n": non_negative("N"),
        "max_rate_n_per_s": non_negative("N/s"),
        "drop_distance_m": non_negative("m"),
        "grasp_s": non_negative("s"),
        "rise_s": non_negative("s"),
        "hold_s": non_negative("s"),
        "pull_s": non_negative("s"),
        "ramp_s": non_negative("s"),
        "lower_s": non_negative("s"),
        "settle_s": non_negative("s"),
        "gap_s": non_negative("s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
        if self.mu_kinetic > self.mu_static:
            raise ConfigError(f"GraspParams: friction needs mu_kinetic <= mu_static, got "
                              f"{self.mu_kinetic!r} > {self.mu_static!r}: lower mu_kinetic "
                              "or raise mu_static")
        if self.hold_s < self.pull_s + 2 * self.ramp_s:
            raise ConfigError(f"GraspParams: hold_s = {self.hold_s!r} is shorter than the pull "
                              f"and its ramps (pull_s + 2 ramp_s = "
                              f"{self.pull_s + 2 * self.ramp_s:g} s): lengthen the hold")
        if self.initial_grip_n > self.max_grip_n:
            raise ConfigError(f"GraspParams: initial_grip_n = {self.initial_grip_n!r} N is "
                              f"above max_grip_n = {self.max_grip_n!r} N: lower it or raise "
                              "max_grip_n")

    @property
    def weight_n(self) -> float:
        """The load (N) while held: m·g."""
        return self.mass_kg * G_M_PER_S2

    @property
    def slip_ratio(self) -> float:
        """Grip/load below which the object slides: 1/mu_static."""
        return 1.0 / self.mu_static

    @property
    def lift_s(self) -> float:
        """One lift's contact (s), without the gap."""
        return self.grasp_s + self.rise_s + self.hold_s + self.lower_s + self.settle_s

    @property
    def period_s(self) -> float:
        """From one lift's start to the next (s)."""
        return self.lift_s + self.gap_s

    def pull_start_s(self, lift: Lift | None = None) -> float:
        """When the pull starts to ramp up (s from the lift's start): the middle of the hold,
        or ``lift``'s own place in it."""
        t2 = (self.grasp_s if lift is None else lift.grasp_s) + self.rise_s
        if lift is None:
            return t2 + 0.5 * (self.hold_s - self.pull_s) - self.ramp_s
        return t2 + lift.pull_at_s

    def pull_end_s(self, lift: Lift | None = None) -> float:
        """When the pull has ramped down (s from the lift's start)."""
        return self.pull_start_s(lift) + 2 * self.ramp_s + self.pull_s

    def lift_duration_s(self, lift: Lift | None = None) -> float:
        """One lift's contact (s): :attr:`lift_s`, or ``lift``'s with its own grasp time."""
        if lift is None:
            return self.lift_s
        return lift.grasp_s + self.rise_s + self.hold_s + self.lower_s + self.settle_s

    def load_keyframes(self, lift: Lift | None = None) -> np.ndarray:
        """(t_s, load_n) of one lift's load profile (module docstring): the object of these
        parameters, or ``lift``'s object, grasp time and pull."""
        w = self.weight_n if lift is None else lift.mass_kg * G_M_PER_S2
        p = self.pull_n if lift is None else lift.pull_n
        t1 = self.grasp_s if lift is None else lift.grasp_s
        t2 = t1 + self.rise_s
        tp = self.pull_start_s(lift)
        t3 = t2 + self.hold_s
        t4 = t3 + self.lower_s
        rows = [(0.0, 0.0), (t1, 0.0), (t2, w), (tp, w), (tp + self.ramp_s, w + p),
                (tp + self.ramp_s + self.pull_s, w + p), (tp + 2 * self.ramp_s + self.pull_s, w),
                (t3, w), (t4, 0.0), (t4 + self.settle_s, 0.0)]
        return np.array(rows)


@dataclass(frozen=True)
class Lift:
    """One lift of a drawn run (SI units): it starts at ``start_s`` (s, scene time), the
    hand closes for ``grasp_s`` (s) before the rise, the object weighs ``mass_kg`` and
    breaks under a grip above ``break_n`` (N; inf: never), and a pull of ``pull_n`` (N)
    starts to ramp up ``pull_at_s`` (s) after the hold starts (unannounced: its time and size
    are the run's secret)."""

    start_s: float
    mass_kg: float
    break_n: float = math.inf
    grasp_s: float = 0.15
    pull_n: float = 0.15
    pull_at_s: float = 0.155

    _parameter_constraints: ClassVar[Constraints] = {
        "start_s": non_negative("s"),
        "mass_kg": positive("kg"),
        "break_n": Interval(Real, 0, math.inf, closed="right", unit="N"),
        "grasp_s": non_negative("s"),
        "pull_n": non_negative("N"),
        "pull_at_s": non_negative("s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)

    def check(self, params: GraspParams) -> Lift:
        """Itself, refused unless it breaks above the hand's initial grip and its pull fits
        in the hold of ``params``."""
        if not self.break_n > params.initial_grip_n:
            raise ConfigError(f"lift at {self.start_s:g} s: break_n {self.break_n!r} must be "
                              f"above the initial grip {params.initial_grip_n:g} N")
        latest = params.hold_s - 2 * params.ramp_s - params.pull_s
        if self.pull_at_s > latest:
            raise ConfigError(f"lift at {self.start_s:g} s: its pull ends after the hold; "
                              f"give pull_at_s <= {latest:g} s")
        return self


@dataclass(frozen=True)
class LiftScene(Scene):
    """A drawn run's scene: one contact per lift and the lifts it was made of."""

    lifts: tuple[Lift, ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        if len(self.lifts) != len(self.contacts):
            raise ConfigError(f"a lift scene needs one lift per contact: {len(self.lifts)} "
                              f"lifts, {len(self.contacts)} contacts")


def _lift_contact(params: GraspParams, lift: Lift | None, start_s: float, name: str) -> Contact:
    load = params.load_keyframes(lift)
    keys = np.column_stack([load[:, 0], load[:, 1], np.zeros(len(load)),
                            np.full(len(load), params.initial_grip_n)])
    trajectory = Trajectory(keys, normal="force", tangential="force")
    pad = Indenter("flat", params.pad_radius_m)
    return Contact(pad, trajectory, start_s, params.mu_static, params.mu_kinetic, name)


def drawn_lift_scene(params: GraspParams, lifts: Sequence[Lift]) -> LiftScene:
    """The run of ``lifts`` (each its own object, timing and pull; start times increasing,
    no two lifts overlapping)."""
    if not 1 <= len(lifts) <= MAX_CONTACTS:
        raise ConfigError(f"a run holds 1..{MAX_CONTACTS} lifts, got {len(lifts)}")
    for a, b in zip(lifts, lifts[1:], strict=False):
        if b.start_s < a.start_s + params.lift_duration_s(a):
            raise ConfigError(f"the lift at {b.start_s:g} s starts before the one at "
                              f"{a.start_s:g} s has ended: space them further apart")
    checked = tuple(lift.check(params) for lift in lifts)
    return LiftScene(tuple(_lift_contact(params, lift, lift.start_s, f"lift{i + 1}")
                           for i, lift in enumerate(checked)), checked)


LIFTS_TAIL_S = 0.05
"""Board time (s) a run of lifts goes on after its last lift's period: the last spikes out."""


def lifts_duration_s(params: GraspParams, lifts: int) -> float:
    """Board time (s) a run of ``lifts`` lifts of :func:`lift_scene` lasts, every lift played:
    ``lifts * params.period_s`` and :data:`LIFTS_TAIL_S` (``serve --grasp N`` and
    ``demo --task grasp`` end there)."""
    return round(lifts * params.period_s + LIFTS_TAIL_S, 3)


def lift_scene(params: GraspParams, lifts: int) -> Scene:
    """``lifts`` lifts of the object, one every ``params.period_s`` from scene time 0."""
    if not (isinstance(lifts, int) and 1 <= lifts <= MAX_CONTACTS):
        raise ConfigError(f"a run holds 1..{MAX_CONTACTS} lifts, got {lifts!r}")
    return Scene(tuple(_lift_contact(params, None, i * params.period_s, f"lift{i + 1}")
                       for i in range(lifts)))
