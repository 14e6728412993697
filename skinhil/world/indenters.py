"""Rigid indenters: the shapes that touch the skin, and the height of their lower surface.

Coordinates are the skin's (:mod:`skinhil.model.geometry`: metres, x with the column, y
towards row 1, z up, the top layer at z = 0 at rest, centred on x = y = 0). An indenter is
placed by its axis ``(x, y)`` and the height ``z_tip`` of its lowest point; its lower surface
at ``(x + dx, y + dy)`` is ``z_tip + h(dx, dy)`` inside its footprint:

- ``sphere`` of radius R: ``h = R − sqrt(R² − dx² − dy²)`` for ``dx² + dy² < R²``;
- ``flat``, a flat-ended cylinder of radius R: ``h = 0`` for ``dx² + dy² ≤ R²``;
- ``edge``, a flat bar of width w and length 2R (``radius_m``: its half-length), its long
  axis at ``angle_deg`` from x: ``h = 0`` where ``|across| ≤ w/2`` and ``|along| ≤ R``;
- ``pins``, a square array of flat pins of radius a at pitch p (one pin on the axis),
  within radius R of the axis: ``h = 0`` within a of the nearest pin's centre.

The skin is sampled at its top-layer masses (the spacing, 1 mm by default): a shape finer
than the spacing touches only the masses it covers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import ClassVar, Literal

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import Constraints, Interval, StrOptions, finite, validate_params

Shape = Literal["sphere", "flat", "edge", "pins"]
SHAPES: tuple[Shape, ...] = ("sphere", "flat", "edge", "pins")
"""The shapes, in the order of their codes in the compiled kernel."""
SPHERE, FLAT, EDGE, PINS = range(4)
GEOMETRY_FIELDS = 6
"""Columns of an indenter's packed geometry: R, w/2, cos, sin of the angle, pitch, pin
radius (m)."""
MAX_SIZE_M = 0.1
"""Largest radius, width, pitch (10 cm: a whole hand is 3.3 cm across)."""
_LENGTH = Interval(Real, 0, MAX_SIZE_M, closed="right", unit="m")


@dataclass(frozen=True)
class Indenter:
    """A rigid indenter (module docstring); lengths in metres, the edge's angle in degrees."""

    shape: Shape = "sphere"
    radius_m: float = 2e-3
    """Sphere or cylinder radius; the edge's half-length; the pin array's extent."""
    width_m: float = 1e-3
    """The edge's width."""
    angle_deg: float = 90.0
    """The edge's long axis from x (90: along y, so that it lies across a slide along x)."""
    pitch_m: float = 2e-3
    """The pin array's pitch."""
    pin_radius_m: float = 0.4e-3
    """Each pin's radius."""

    _parameter_constraints: ClassVar[Constraints] = {
        "shape": StrOptions(SHAPES),
        "radius_m": _LENGTH,
        "width_m": _LENGTH,
        "pitch_m": _LENGTH,
        "pin_radius_m": _LENGTH,
        "angle_deg": finite("degrees"),
    }

    def __post_init__(self) -> None:
        validate_params(self, where="indenter ")
        if self.shape == "pins" and self.pin_radius_m * 2 >= self.pitch_m:
            raise ConfigError("indenter pins: pin_radius_m must be less than half the "
                              "pitch_m (pins that touch are a flat)")

    @property
    def code(self) -> int:
        """The shape's code in the compiled kernel."""
        return SHAPES.index(self.shape)

    @property
    def reach_m(self) -> float:
        """Distance (m) from the axis beyond which the indenter touches nothing."""
        if self.shape == "edge":
            return math.hypot(self.radius_m, 0.5 * self.width_m)
        return self.radius_m

    def geometry(self) -> np.ndarray:
        """The packed geometry (:data:`GEOMETRY_FIELDS` floats) the kernel reads."""
        a = math.radians(self.angle_deg)
        return np.array([self.radius_m, 0.5 * self.width_m, math.cos(a), math.sin(a),
                         self.pitch_m, self.pin_radius_m])


@numba.njit(inline="always")
def surface_height(shape: int, geo: np.ndarray, dx: float,
                   dy: float) -> float:  # pragma: no cover - compiled
    """Height (m) of the indenter's lower surface above its tip at ``(dx, dy)`` (m) from its
    axis; −1 outside its footprint (module docstring)."""
    r = geo[0]
    r2 = dx * dx + dy * dy
    if shape == SPHERE:
        if r2 >= r * r:
            return -1.0
        return r - math.sqrt(r * r - r2)
    if shape == FLAT:
        return 0.0 if r2 <= r * r else -1.0
    if shape == EDGE:
        along = geo[2] * dx + geo[3] * dy
        across = -geo[3] * dx + geo[2] * dy
        return 0.0 if abs(across) <= geo[1] and abs(along) <= r else -1.0
    if r2 > r * r:  # pins
        return -1.0
    p = geo[4]
    ex = dx - p * math.floor(dx / p + 0.5)
    ey = dy - p * math.floor(dy / p + 0.5)
    return 0.0 if ex * ex + ey * ey <= geo[5] * geo[5] else -1.0
