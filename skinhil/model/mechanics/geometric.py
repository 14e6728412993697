"""The ``geometric`` mechanics: true spring lengths, for large deformations.

Each spring ``s`` between masses ``i`` and ``j`` (current positions ``p``, velocities ``v``,
rest length ``L0``) pulls along its current direction ``e = (p_j − p_i)/L``, ``L = |p_j − p_i|``:

    f_s = k (L − L0) + T + c eᵀ(v_j − v_i)        (N, positive in tension)

acting as ``+f_s e`` on ``i`` and ``−f_s e`` on ``j``. The net force the springs exert at rest
(the baseline tension ``T`` pulls layer 1 downwards) is subtracted, as if held by the
surrounding tissue, so the rest mesh is an equilibrium and the linearisation about it is
exactly the ``linear`` mechanics (axial K, geometric stiffness ``T/L0 (I − e eᵀ)``, axial C).
Fixed masses do not move; ``M p'' = F_springs + f_ext`` on the free masses.

Integrator: classical 4th-order Runge–Kutta at the fixed step ``dt``, with the external force
held over the step (zero-order hold, as the linear mechanics). Global error O(dt⁴); with zero
damping the energy error is O(dt⁴) too. Explicit, so ``dt`` must resolve the fastest mode in
any configuration the mesh can take: :func:`max_stable_dt` gives that bound and the model
refuses larger steps.

The sensor signal is ``k (L − L0)`` (N): Hooke's force of the spring alone, without ``T``
(the length readout); ``readout="axial"`` reports ``k e0ᵀ(q_j − q_i)`` instead, with ``e0`` the
rest direction and ``q`` the displacements from rest, the small-displacement form the linear
mechanics can also report (:mod:`skinhil.model.mechanics.readout`, which computes both).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from skinhil.model.geometry import Mesh
from skinhil.model.mechanics.readout import Readout, spring_signal

RK4_STABILITY_RADIUS = 2.5
"""|λ|·dt bound used for RK4 (its real-axis limit is 2.785, imaginary-axis 2.828)."""


@numba.njit(inline="always", fastmath=True)
def _spring_vector(p: np.ndarray, springs: np.ndarray,
                   s: int) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """The vector from spring ``s``'s first mass to its second, and its length (m)."""
    i = springs[s, 0]
    j = springs[s, 1]
    dx = p[j, 0] - p[i, 0]
    dy = p[j, 1] - p[i, 1]
    dz = p[j, 2] - p[i, 2]
    return dx, dy, dz, np.sqrt(dx * dx + dy * dy + dz * dz)


@numba.njit(cache=True, fastmath=True)
def _spring_forces(p: np.ndarray, v: np.ndarray, springs: np.ndarray, rest: np.ndarray,
                   k: float, c: float, t: float, live: np.ndarray,
                   out: np.ndarray) -> None:  # pragma: no cover
    # the springs' net force (N) on every mass, from the springs ``live`` only
    out[:] = 0.0
    for s in live:
        i = springs[s, 0]
        j = springs[s, 1]
        dx, dy, dz, length = _spring_vector(p, springs, s)
        if length <= 0.0:
            continue
        ex = dx / length
        ey = dy / length
        ez = dz / length
        vel = ex * (v[j, 0] - v[i, 0]) + ey * (v[j, 1] - v[i, 1]) + ez * (v[j, 2] - v[i, 2])
        f = k * (length - rest[s]) + t + c * vel
        out[i, 0] += f * ex
        out[i, 1] += f * ey
        out[i, 2] += f * ez
        out[j, 0] -= f * ex
        out[j, 1] -= f * ey
        out[j, 2] -= f * ez


@numba.njit(cache=True, fastmath=True, nogil=True)
def _rk4_kernel(p: np.ndarray, v: np.ndarray, springs: np.ndarray, rest: np.ndarray,
                k: float, c: float, t: float, preload: np.ndarray, free: np.ndarray,
                inv_m: float, dt: float, f_ext: np.ndarray, out: np.ndarray,
                rest_p: np.ndarray, ke: np.ndarray, length: bool,
                live: np.ndarray) -> None:  # pragma: no cover - compiled
    n = p.shape[0]
    rk4_steps(p, v, springs, rest, k, c, t, preload, free, inv_m, dt, f_ext, out, rest_p, ke,
              length, live, np.empty((n, 3)), np.zeros((4, n, 3)), np.zeros((4, n, 3)),
              p.copy(), v.copy())


@numba.njit(cache=True, fastmath=True, nogil=True)
def rk4_steps(p: np.ndarray, v: np.ndarray, springs: np.ndarray, rest: np.ndarray,
              k: float, c: float, t: float, preload: np.ndarray, free: np.ndarray,
              inv_m: float, dt: float, f_ext: np.ndarray, out: np.ndarray,
              rest_p: np.ndarray, ke: np.ndarray, length: bool, live: np.ndarray,
              fbuf: np.ndarray, kp: np.ndarray, kv: np.ndarray, ps: np.ndarray,
              vs: np.ndarray) -> None:  # pragma: no cover - compiled
    """:func:`_rk4_kernel`'s steps with its scratch given (fbuf (n, 3), kp and kv (4, n, 3),
    ps and vs (n, 3)): a caller stepping one step at a time allocates it once."""
    weights = (0.5, 0.5, 1.0)
    for step in range(f_ext.shape[0]):
        for s in range(springs.shape[0]):  # the readout of d = q_j − q_i, q = p − rest_p
            i = springs[s, 0]
            j = springs[s, 1]
            out[step, s] = spring_signal(
                ke[s, 0], ke[s, 1], ke[s, 2], p[j, 0] - p[i, 0] - (rest_p[j, 0] - rest_p[i, 0]),
                p[j, 1] - p[i, 1] - (rest_p[j, 1] - rest_p[i, 1]),
                p[j, 2] - p[i, 2] - (rest_p[j, 2] - rest_p[i, 2]), k, rest[s], length)
        for stage in range(4):
            if stage == 0:
                ps[:] = p
                vs[:] = v
            else:
                h = weights[stage - 1] * dt
                for m in free:
                    for a in range(3):
                        ps[m, a] = p[m, a] + h * kp[stage - 1, m, a]
                        vs[m, a] = v[m, a] + h * kv[stage - 1, m, a]
            _spring_forces(ps, vs, springs, rest, k, c, t, live, fbuf)
            for m in free:
                for a in range(3):
                    kp[stage, m, a] = vs[m, a]
                    kv[stage, m, a] = (fbuf[m, a] - preload[m, a] + f_ext[step, m, a]) * inv_m
        for m in free:
            for a in range(3):
                p[m, a] += dt / 6.0 * (kp[0, m, a] + 2.0 * kp[1, m, a] + 2.0 * kp[2, m, a]
                                       + kp[3, m, a])
                v[m, a] += dt / 6.0 * (kv[0, m, a] + 2.0 * kv[1, m, a] + 2.0 * kv[2, m, a]
                                       + kv[3, m, a])


def max_stable_dt(mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                  damping_n_s_per_m: float, tension_n: float) -> float:
    """Largest RK4 step (s) that is stable in any configuration of the mesh.

    The linearisation at rest is not enough: as the mesh deforms, the springs at a mass turn
    towards one direction and the damping and stiffness it feels add up along it (a 4x
    smaller stable step was seen at C = 0.2 N·s/m, K = 30 N/m under 0.5 N). Whatever the
    directions, a spring's 3x3 blocks have norm ``c`` and ``k + T/L0``, so by Gershgorin the
    eigenvalues satisfy ``|λ| ≤ γ + ω`` with ``γ = 2·deg·c/m`` and ``ω² = 2·deg·(k + T/L0)/m``
    (``deg`` the most springs at a free mass, ``L0`` the shortest rest length); the step is
    ``RK4_STABILITY_RADIUS / (γ + ω)``.
    """
    free = ~mesh.fixed
    deg = int(np.bincount(mesh.springs.ravel(), minlength=free.size)[free].max())
    d = mesh.positions[mesh.springs[:, 1]] - mesh.positions[mesh.springs[:, 0]]
    shortest = float(np.linalg.norm(d, axis=1).min())
    gamma = 2.0 * deg * damping_n_s_per_m / mass_kg
    omega = math.sqrt(2.0 * deg * (stiffness_n_per_m + tension_n / shortest) / mass_kg)
    return RK4_STABILITY_RADIUS / (gamma + omega)


class GeometricMechanics:
    """RK4 stepper of the geometric mechanics at a fixed ``dt_s`` (see module docstring)."""

    def __init__(self, mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                 damping_n_s_per_m: float, tension_n: float, dt_s: float,
                 readout: Readout = "length") -> None:
        self.mesh = mesh
        self.readout = readout
        """What each spring reports (:mod:`skinhil.model.mechanics.readout`)."""
        self.rest_positions = mesh.positions.copy()
        self.springs = np.ascontiguousarray(mesh.springs)
        d = mesh.positions[mesh.springs[:, 1]] - mesh.positions[mesh.springs[:, 0]]
        self.rest_lengths = np.linalg.norm(d, axis=1)
        self.ke = stiffness_n_per_m * d / self.rest_lengths[:, None]
        self.k, self.c, self.t = stiffness_n_per_m, damping_n_s_per_m, tension_n
        self.inv_m = 1.0 / mass_kg
        self.mass_kg = mass_kg
        self.dt_s = dt_s
        self.free = np.ascontiguousarray(mesh.free)
        self.live = np.flatnonzero(~mesh.fixed[mesh.springs].all(axis=1))
        """The springs with a free end: a spring between two fixed masses never moves and
        pulls on fixed masses only, so the dynamics skip it (137 of 338 at 6x6)."""
        self.preload = np.empty_like(mesh.positions)
        _spring_forces(self.rest_positions, np.zeros_like(self.rest_positions), self.springs,
                       self.rest_lengths, self.k, self.c, self.t, self.live, self.preload)
        self.p = self.rest_positions.copy()
        self.v = np.zeros_like(self.p)

    def reset(self) -> None:
        """Back to rest: rest positions, zero velocity."""
        self.p[:] = self.rest_positions
        self.v[:] = 0.0

    def displacement_m(self) -> np.ndarray:
        """Every mass's displacement from rest now (n_masses, 3) m; fixed masses 0."""
        return self.p - self.rest_positions

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """Step ``len(forces_n)`` steps; ``forces_n`` is (n, 77, 3) N; returns (n, 338) N.

        Row ``j`` of the result is the spring forces at the start of step ``j``; input ``j`` is
        then held over the step.
        """
        f_ext = np.ascontiguousarray(forces_n, dtype=np.float64)
        out = np.empty((f_ext.shape[0], self.springs.shape[0]))
        _rk4_kernel(self.p, self.v, self.springs, self.rest_lengths, self.k, self.c, self.t,
                    self.preload, self.free, self.inv_m, self.dt_s, f_ext, out,
                    self.rest_positions, self.ke, self.readout == "length", self.live)
        return out

    def energy_j(self) -> float:
        """Mechanical energy (J): kinetic + Σ ½k(L − L0)² + T(L − L0) + preload·(p − p0)."""
        d = self.p[self.springs[:, 1]] - self.p[self.springs[:, 0]]
        ext = np.linalg.norm(d, axis=1) - self.rest_lengths
        kinetic = 0.5 * self.mass_kg * float(np.sum(self.v[self.free] ** 2))
        elastic = float(np.sum(0.5 * self.k * ext**2 + self.t * ext))
        moved = (self.p - self.rest_positions)[self.free]
        return kinetic + elastic + float(np.sum(self.preload[self.free] * moved))
