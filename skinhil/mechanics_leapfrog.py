"""The ``linear`` mechanics for large meshes: a leapfrog stepper of cost O(springs) per step.

Same equations as :mod:`skinhil.mechanics_linear` (``M q'' + C q' + K q = f`` on the free
masses, axial springs and dampers plus the geometric stiffness ``T/L (I − e eᵀ)`` of a
baseline tension), never assembled: each step makes one pass over the springs, reading the
displacements and velocities of its two masses and adding its force to both, so a step costs
O(springs) time and memory where the exact ZOH of :mod:`skinhil.mechanics_linear` costs
O(dof²). The model uses it above ``EXACT_MAX_FREE_DOFS`` free degrees of freedom
(:mod:`skinhil.skin`).

Scheme (kick-drift leapfrog, velocities at half steps; ``h = dt``, ``m`` the nodal mass):

    w_n       = v_{n−½} + (h/2)·a_{n−1}                 (velocity at t_n, extrapolated)
    a_n       = (−K q_n − C w_n + (f_{n−1} + f_n)/2) / m
    v_{n+½}   = v_{n−½} + h·a_n
    q_{n+1}   = q_n + h·v_{n+½}

from rest (``q_0 = v_{−½} = a_{−1} = f_{−1} = 0``). ``(f_{n−1} + f_n)/2`` is the exact impulse
of the zero-order-held input over ``[t_{n−½}, t_{n+½}]``, so the scheme approximates the same
ZOH system as the exact stepper. Without damping it is Störmer–Verlet (symplectic, second
order); the extrapolated velocity in the damping term is exact to O(h²), so the scheme is
second order overall: the global error of the spring forces falls 4x per halving of ``dt``
(tests/test_core_leapfrog.py measures the order and the error against ``solve_ivp``). At the
default parameters and dt = 0.1 ms (fastest mode ω·dt ≈ 0.2) the largest error of the spring
forces under paper stimulus A is 0.13 % of their peak at 6x6 and 16x16.

Explicit, so the step must resolve the fastest mode. For one mode ``q'' + γ q' + ω² q = f/m``
the scheme is stable for ``γ·h + (ω·h)²/4 < 1`` (the undamped limit ω·h < 2 of Störmer–Verlet,
the limit γ·h < 1 of the extrapolated damping, and between them this curve, computed from the
3x3 step map); with ``ω`` and ``γ`` the largest rates of ``M⁻¹K`` and ``M⁻¹C`` (sparse
eigenvalue estimates, :func:`fastest_rates`) each step of ``dt`` is cut into the fewest equal
substeps ``h`` that keep ``γ·h + (ω·h)²/4 ≤ 0.9`` and, for accuracy, ``ω·h ≤ 0.25``
(:func:`substeps_for`), the input held over all of them. At the default parameters ω ≈ 2,050
rad/s and γ ≈ 4,200 /s at every size: one substep at dt = 0.1 ms; a baseline tension of 0.5 N
(ω ≈ 7,600 rad/s) takes 4. The cost per step grows with the substeps.

The sensor signal of spring ``s`` is ``k eᵀ(q_j − q_i)`` (N) at the start of each step, as in
the exact stepper.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.sparse.linalg import eigsh

from skinhil.geometry import Mesh
from skinhil.mechanics_linear import assemble, free_block, spring_frames

STABILITY_BOUND = 0.9
"""Substeps are chosen so that ``γ·h + (ω·h)²/4`` stays below this (the scheme's limit is 1)."""
ACCURACY_OMEGA_H = 0.25
"""... and so that ``ω·h`` stays below this: the fastest mode's phase error per period is then
below ``(ω·h)²/24`` ≈ 0.3 %."""

TINY = 1e-150
"""State components below this are flushed to zero (subnormals are ~100x slower on x86)."""

LeapfrogOperands = tuple[np.ndarray, np.ndarray, np.ndarray, float, float, float,
                         np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""``LeapfrogMechanics.operands``: springs, unit vectors e, T/L, k, c, 1/m, free masses, then
the state q, v, w (velocity at the step start), f_prev; arrays updated in place."""


@numba.njit(cache=True, fastmath=True, nogil=True)
def leapfrog_kernel(forces: np.ndarray, out: np.ndarray, dt: float, substeps: int,
                    springs: np.ndarray, e: np.ndarray, t_over_l: np.ndarray, k: float,
                    c: float, inv_m: float, free: np.ndarray, q: np.ndarray, v: np.ndarray,
                    w: np.ndarray, f_prev: np.ndarray) -> None:  # pragma: no cover - compiled
    """forces (n, n_masses, 3) N held per step of ``dt`` (s), each in ``substeps`` leapfrog
    steps → out (n, n_springs) N; the operands after ``substeps`` are
    :attr:`LeapfrogMechanics.operands`."""
    n_masses = q.shape[0]
    acc = np.zeros((n_masses, 3))
    h = dt / substeps
    for step in range(forces.shape[0]):
        fs = forces[step]
        for sub in range(substeps):
            acc[:] = 0.0
            row = out[step]
            for s in range(springs.shape[0]):
                i = springs[s, 0]
                j = springs[s, 1]
                ex = e[s, 0]
                ey = e[s, 1]
                ez = e[s, 2]
                dx = q[j, 0] - q[i, 0]
                dy = q[j, 1] - q[i, 1]
                dz = q[j, 2] - q[i, 2]
                ext = ex * dx + ey * dy + ez * dz
                rate = (ex * (w[j, 0] - w[i, 0]) + ey * (w[j, 1] - w[i, 1])
                        + ez * (w[j, 2] - w[i, 2]))
                if sub == 0:
                    row[s] = k * ext
                tl = t_over_l[s]
                axial = k * ext + c * rate - tl * ext
                fx = axial * ex + tl * dx
                fy = axial * ey + tl * dy
                fz = axial * ez + tl * dz
                acc[i, 0] += fx
                acc[i, 1] += fy
                acc[i, 2] += fz
                acc[j, 0] -= fx
                acc[j, 1] -= fy
                acc[j, 2] -= fz
            for m in free:
                for a in range(3):
                    f_now = fs[m, a]
                    am = (acc[m, a] + 0.5 * (f_prev[m, a] + f_now)) * inv_m
                    f_prev[m, a] = f_now
                    vm = v[m, a] + h * am
                    qm = q[m, a] + h * vm
                    wm = vm + 0.5 * h * am
                    v[m, a] = vm if abs(vm) > TINY else 0.0
                    q[m, a] = qm if abs(qm) > TINY else 0.0
                    w[m, a] = wm if abs(wm) > TINY else 0.0


def fastest_rates(mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                  damping_n_s_per_m: float, tension_n: float) -> tuple[float, float]:
    """``(ω_max, γ_max)``: the largest eigenvalue's square root of ``M⁻¹K`` (rad/s) and the
    largest eigenvalue of ``M⁻¹C`` (1/s) on the free masses, from the sparse matrices."""
    k_glob, c_glob = assemble(mesh, stiffness_n_per_m, damping_n_s_per_m, tension_n)
    out = []
    for glob in (k_glob, c_glob):
        block = free_block(glob, mesh)
        if block.shape[0] <= 3 or not np.any(block.data):
            lam = float(np.linalg.eigvalsh(block.toarray()).max()) if block.shape[0] else 0.0
        else:
            lam = float(eigsh(block, k=1, which="LA", return_eigenvectors=False,
                              tol=1e-6)[0])
        out.append(max(lam, 0.0) / mass_kg)
    return math.sqrt(out[0]), out[1]


def substeps_for(omega: float, gamma: float, dt_s: float) -> int:
    """Leapfrog substeps per step of ``dt_s`` (s) so that each substep ``h`` satisfies
    ``γ·h + (ω·h)²/4 ≤ STABILITY_BOUND`` and ``ω·h ≤ ACCURACY_OMEGA_H`` (module docstring)."""
    n = max(1, math.ceil(omega * dt_s / ACCURACY_OMEGA_H))
    while gamma * dt_s / n + (omega * dt_s / n) ** 2 / 4.0 > STABILITY_BOUND:
        n += 1
    return n


class LeapfrogMechanics:
    """Leapfrog stepper of the linear mechanics at a fixed ``dt_s`` (see module docstring)."""

    def __init__(self, mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                 damping_n_s_per_m: float, tension_n: float, dt_s: float) -> None:
        e, length = spring_frames(mesh)
        n = mesh.positions.shape[0]
        self.dt_s = dt_s
        self.omega_max, self.gamma_max = fastest_rates(mesh, mass_kg, stiffness_n_per_m,
                                                       damping_n_s_per_m, tension_n)
        self.substeps = substeps_for(self.omega_max, self.gamma_max, dt_s)
        self.n_masses = n
        self.n_springs = mesh.springs.shape[0]
        self.q = np.zeros((n, 3))
        self.v = np.zeros((n, 3))
        self.w = np.zeros((n, 3))
        self.f_prev = np.zeros((n, 3))
        self.operands: LeapfrogOperands = (
            np.ascontiguousarray(mesh.springs), np.ascontiguousarray(e),
            np.ascontiguousarray(tension_n / length), float(stiffness_n_per_m),
            float(damping_n_s_per_m), 1.0 / mass_kg, np.ascontiguousarray(mesh.free),
            self.q, self.v, self.w, self.f_prev)

    def reset(self) -> None:
        """Back to rest: zero displacement, velocity and held input."""
        for arr in (self.q, self.v, self.w, self.f_prev):
            arr[:] = 0.0

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """Step ``len(forces_n)`` steps; ``forces_n`` is (n, n_masses, 3) N; returns
        (n, n_springs) N, row ``j`` the spring forces at the start of step ``j``."""
        forces = np.ascontiguousarray(forces_n, dtype=np.float64)
        out = np.empty((forces.shape[0], self.n_springs))
        leapfrog_kernel(forces, out, self.dt_s, self.substeps, *self.operands)
        return out
