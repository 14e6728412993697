"""What a spring reports: its length change (default) or the axial projection (the
small-displacement limit).

Every mechanics computes its sensor signal here, where the forces leave the stepper. For the
spring ``s`` between masses ``i`` and ``j`` with rest unit vector ``e`` (from ``i`` to ``j``),
rest length ``L0``, stiffness ``k`` and relative displacement ``d = q_j − q_i`` (m):

- ``"length"`` — Hooke's law on the spring's length, ``k·(|L0·e + d| − L0)`` (N): how far the
  spring is from its equilibrium length (the paper: "x is the rate of change from its
  equilibrium position"). Computed as ``k·(2·L0·eᵀd + |d|²) / (|L0·e + d| + L0)``, the same
  number without the cancellation of two nearly equal lengths when ``d`` is small.
- ``"axial"`` — ``k·eᵀd`` (N): the first-order term of the above in ``|d|/L0``, exact only
  for small displacements. At the paper's forces (0.5 N on a 1 mm mesh at 50 N/m) the linear
  mesh moves several rest lengths, where the two differ in sign and size
  (docs/figures/REPORT.md, "Regime").

Both are positive in tension. The geometric mechanics' positions give ``d`` exactly as well,
so both readouts exist for both mechanics (``SkinParams.readout``).
"""

from __future__ import annotations

import math
from typing import Literal

import numba
import numpy as np

Readout = Literal["length", "axial"]
Real = float | np.floating
"""A real of either precision: the kernels compute in their state's (float64 or float32)."""
READOUTS: tuple[Readout, ...] = ("length", "axial")


@numba.njit(inline="always", fastmath=True)
def spring_signal(ke_x: Real, ke_y: Real, ke_z: Real, dx: Real, dy: Real, dz: Real, k: Real,
                  rest_m: Real, length: bool) -> Real:  # pragma: no cover
    """A spring's sensor force (N) from ``k·e`` (N/m), its relative displacement ``d`` (m),
    ``k`` (N/m) and its rest length (m): the length change (``length``) or the axial
    projection (module docstring). Computed in the precision of its arguments (no float64
    constant promotes single-precision ones): ``2·L0`` as ``L0 + L0``, the same number."""
    proj = ke_x * dx + ke_y * dy + ke_z * dz  # k eᵀd
    if not length:
        return proj
    d2 = dx * dx + dy * dy + dz * dz
    squared = rest_m * rest_m + (rest_m + rest_m) * proj / k + d2  # |L0·e + d|², >= 0 but
    return length_signal(proj, d2, math.sqrt(max(squared, d2 - d2)), k, rest_m)  # for rounding


@numba.njit(inline="always", fastmath=True)
def length_signal(proj: Real, d2: Real, now: Real, k: Real,
                  rest_m: Real) -> Real:  # pragma: no cover - compiled
    """The length readout (N) of a spring of rest length ``rest_m`` (m) whose relative
    displacement ``d`` has ``k eᵀd = proj`` (N) and ``|d|² = d2`` (m²) and whose length is
    ``now`` (m) (a kernel that has the length already passes it):
    ``k·(2·L0·eᵀd + |d|²) / (now + L0)``, the length change without cancellation."""
    return ((rest_m + rest_m) * proj + k * d2) / (now + rest_m)
