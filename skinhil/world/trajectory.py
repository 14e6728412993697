"""How an indenter moves: keyframes of its place and depth (or load) over time, a vibration.

A trajectory is a table of keyframes ``(t_s, x_m, y_m, value)`` from the contact's start,
linearly interpolated between them and held outside (the contact ends at the last keyframe):

- ``normal = "position"``: ``value`` is the depth (m) of the indenter's tip below the rest
  surface (``z_tip = −depth``); the builders :meth:`Trajectory.press`,
  :meth:`Trajectory.slide` and :meth:`Trajectory.taps` write such tables;
- ``normal = "force"``: ``value`` is the normal load (N) the indenter holds: its tip moves at
  ``dz/dt = −b_n·(load − N)`` (an admittance, ``ContactParams.admittance_m_per_n_s``), from
  the rest surface, so it settles where the skin pushes back with the load; the load can be
  replaced while running (a grip set-point, :meth:`skinhil.world.scene.World.set_load`).
- ``tangential = "force"`` (Python API): ``x``, ``y`` are a tangential load (N) the indenter
  applies, its axis moving from ``origin_m`` at ``d(x, y)/dt = b_t·(load − F_t)``.

A vibration ``amplitude_m · sin(2π·frequency_hz·t)`` along ``x``, ``y`` or ``z`` (depth) is
added to any positional axis.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import (
    Constraints,
    StrOptions,
    check_param,
    non_negative,
    positive,
    validate_params,
)

Control = Literal["position", "force"]
CONTROLS: tuple[Control, ...] = ("position", "force")
AXES = ("x", "y", "z")
MAX_KEYFRAMES = 10_000
"""Most keyframes of one trajectory."""


@dataclass(frozen=True)
class Trajectory:
    """Keyframes (K, 4): t (s from the contact's start, increasing), x, y (m, or N for a
    tangential load), depth (m) or normal load (N); see the module docstring."""

    keyframes: np.ndarray
    normal: Control = "position"
    tangential: Control = "position"
    vibration_amplitude_m: float = 0.0
    vibration_frequency_hz: float = 0.0
    vibration_axis: str = "z"
    origin_m: tuple[float, float] = (0.0, 0.0)
    """Start of the axis under a tangential load (``tangential = "force"``)."""

    _parameter_constraints: ClassVar[Constraints] = {
        "normal": StrOptions(CONTROLS),
        "tangential": StrOptions(CONTROLS),
        "vibration_amplitude_m": non_negative("m"),
        "vibration_frequency_hz": non_negative("Hz"),
        "vibration_axis": StrOptions(AXES),
    }

    def __post_init__(self) -> None:
        k = np.array(self.keyframes, dtype=np.float64)
        if k.ndim != 2 or k.shape[1] != 4 or not 1 <= k.shape[0] <= MAX_KEYFRAMES:
            raise ConfigError(f"a trajectory is 1..{MAX_KEYFRAMES} keyframes of (t_s, x, y, "
                              f"depth or load), got shape {k.shape}")
        if not np.isfinite(k).all() or k[0, 0] < 0 or np.any(np.diff(k[:, 0]) < 0):
            raise ConfigError("trajectory keyframes must be finite with times >= 0 in "
                              "increasing order")
        validate_params(self, where="trajectory ")
        if self.normal == "force" and np.any(k[:, 3] < 0):
            raise ConfigError("a normal load must be >= 0 N")
        vib_on = self.vibration_amplitude_m > 0
        if vib_on and ((self.vibration_axis == "z" and self.normal == "force")
                       or (self.vibration_axis != "z" and self.tangential == "force")):
            raise ConfigError("a vibration moves a position-controlled axis: not the "
                              "force-controlled one")
        k.setflags(write=False)
        object.__setattr__(self, "keyframes", k)

    @property
    def duration_s(self) -> float:
        """Time (s) from the contact's start to its end (the last keyframe)."""
        return float(self.keyframes[-1, 0])

    def with_vibration(self, amplitude_m: float, frequency_hz: float,
                       axis: str = "z") -> Trajectory:
        """This trajectory with a sinusoidal vibration added (module docstring)."""
        return Trajectory(self.keyframes, self.normal, self.tangential, amplitude_m,
                          frequency_hz, axis, self.origin_m)

    @staticmethod
    def press(x_m: float, y_m: float, depth_m: float, ramp_s: float = 0.02,
              hold_s: float = 0.2, load: bool = False) -> Trajectory:
        """Press at ``(x, y)`` to ``depth_m`` (or to a load of ``depth_m`` N with
        ``load=True``) over ``ramp_s``, hold ``hold_s``, release over ``ramp_s``."""
        ramp = max(ramp_s, 0.0)
        k = [(0.0, x_m, y_m, 0.0), (ramp, x_m, y_m, depth_m),
             (ramp + hold_s, x_m, y_m, depth_m), (2 * ramp + hold_s, x_m, y_m, 0.0)]
        return Trajectory(np.array(k), "force" if load else "position")

    @staticmethod
    def slide(start_m: Sequence[float], end_m: Sequence[float], speed_m_per_s: float,
              depth_m: float, ramp_s: float = 0.02, dwell_s: float = 0.05,
              load: bool = False) -> Trajectory:
        """Press at ``start_m`` (x, y) over ``ramp_s``, dwell ``dwell_s``, slide in a straight
        line to ``end_m`` at ``speed_m_per_s``, dwell, lift over ``ramp_s``."""
        check_param("speed_m_per_s", speed_m_per_s, positive("m/s"))
        (x0, y0), (x1, y1) = start_m, end_m
        travel = math.hypot(x1 - x0, y1 - y0) / speed_m_per_s
        t1 = ramp_s + dwell_s
        t2 = t1 + travel
        k = [(0.0, x0, y0, 0.0), (ramp_s, x0, y0, depth_m), (t1, x0, y0, depth_m),
             (t2, x1, y1, depth_m), (t2 + dwell_s, x1, y1, depth_m),
             (t2 + dwell_s + ramp_s, x1, y1, 0.0)]
        return Trajectory(np.array(k), "force" if load else "position")

    @staticmethod
    def taps(x_m: float, y_m: float, depth_m: float, count: int, period_s: float,
             contact_s: float) -> Trajectory:
        """``count`` taps at ``(x, y)``: each a triangle to ``depth_m`` and back lasting
        ``contact_s``, one every ``period_s``."""
        if not (isinstance(count, int) and count >= 1 and 0 < contact_s <= period_s):
            raise ConfigError("taps: count >= 1 and 0 < contact_s <= period_s")
        k = []
        for i in range(count):
            t0 = i * period_s
            k += [(t0, x_m, y_m, 0.0), (t0 + 0.5 * contact_s, x_m, y_m, depth_m),
                  (t0 + contact_s, x_m, y_m, 0.0)]
        return Trajectory(np.array(k))
