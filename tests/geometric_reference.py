"""The geometric mechanics' former formulation, kept as the reference its strip kernel is
pinned to (tests/test_core_geometric_kernel.py) and the rhs of the solve_ivp comparisons.

Spring by spring over a (spring, 2) index list, in absolute positions ``p`` (n_masses, 3) m:
``L = |p_j − p_i|``, ``e = d/L``, ``f = k (L − L0) + T + c eᵀ(v_j − v_i)`` added as ``+f e``
on ``i`` and ``−f e`` on ``j``; RK4 with the four stages' derivatives stored and combined as
``dt/6 (k1 + 2 k2 + 2 k3 + k4)``; the readout from ``q = p − p0``
(:func:`skinhil.model.mechanics.readout.spring_signal`)."""

from __future__ import annotations

import numba
import numpy as np

from skinhil.model.mechanics.geometric import GeometricMechanics
from skinhil.model.mechanics.readout import spring_signal


@numba.njit(cache=True)
def spring_forces(p: np.ndarray, v: np.ndarray, springs: np.ndarray, rest: np.ndarray,
                  k: float, c: float, t: float, live: np.ndarray,
                  out: np.ndarray) -> None:  # pragma: no cover - compiled
    """The springs' net force (N) on every mass (n_masses, 3) from the springs ``live``."""
    out[:] = 0.0
    for s in live:
        i = springs[s, 0]
        j = springs[s, 1]
        dx = p[j, 0] - p[i, 0]
        dy = p[j, 1] - p[i, 1]
        dz = p[j, 2] - p[i, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
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


@numba.njit(cache=True)
def rk4_steps(p: np.ndarray, v: np.ndarray, springs: np.ndarray, rest: np.ndarray, k: float,
              c: float, t: float, preload: np.ndarray, free: np.ndarray, inv_m: float,
              dt: float, f_ext: np.ndarray, out: np.ndarray, rest_p: np.ndarray,
              ke: np.ndarray, length: bool) -> None:  # pragma: no cover - compiled
    """``len(f_ext)`` RK4 steps of (p, v) under f_ext (n, n_masses, 3) N → out (n, n_springs)
    N, the readouts at each step's start."""
    n = p.shape[0]
    live = np.arange(springs.shape[0])
    fbuf = np.empty((n, 3))
    kp = np.zeros((4, n, 3))
    kv = np.zeros((4, n, 3))
    weights = (0.5, 0.5, 1.0)
    for step in range(f_ext.shape[0]):
        for s in range(springs.shape[0]):
            i = springs[s, 0]
            j = springs[s, 1]
            out[step, s] = spring_signal(
                ke[s, 0], ke[s, 1], ke[s, 2], p[j, 0] - p[i, 0] - (rest_p[j, 0] - rest_p[i, 0]),
                p[j, 1] - p[i, 1] - (rest_p[j, 1] - rest_p[i, 1]),
                p[j, 2] - p[i, 2] - (rest_p[j, 2] - rest_p[i, 2]), k, rest[s], length)
        for stage in range(4):
            ps = p.copy()
            vs = v.copy()
            if stage > 0:
                h = weights[stage - 1] * dt
                for m in free:
                    for a in range(3):
                        ps[m, a] = p[m, a] + h * kp[stage - 1, m, a]
                        vs[m, a] = v[m, a] + h * kv[stage - 1, m, a]
            spring_forces(ps, vs, springs, rest, k, c, t, live, fbuf)
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


class ReferenceGeometric:
    """The former stepper on the geometry and parameters of ``g`` (a
    :class:`GeometricMechanics`), from rest: its own preload, the same interface."""

    def __init__(self, g: GeometricMechanics) -> None:
        self.g = g
        self.p = g.rest_positions.copy()
        self.v = np.zeros_like(self.p)
        self.everything = np.arange(len(g.springs))
        self.preload = self.forces(self.p, self.v)
        d = g.rest_positions[g.springs[:, 1]] - g.rest_positions[g.springs[:, 0]]
        self.ke = g.k * d / g.rest_lengths[:, None]

    def forces(self, p: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The springs' net force (n_masses, 3) N at positions p and velocities v."""
        out = np.empty_like(p)
        g = self.g
        spring_forces(p, v, g.springs, g.rest_lengths, g.k, g.c, g.t, self.everything, out)
        return out

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """As :meth:`GeometricMechanics.advance`."""
        g = self.g
        f = np.ascontiguousarray(forces_n, dtype=np.float64)
        out = np.empty((f.shape[0], len(g.springs)))
        rk4_steps(self.p, self.v, g.springs, g.rest_lengths, g.k, g.c, g.t, self.preload,
                  g.free, g.inv_m, g.dt_s, f, out, g.rest_positions, self.ke,
                  g.readout == "length")
        return out
