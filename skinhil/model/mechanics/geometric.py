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

Layout (as the leapfrog's, :mod:`skinhil.model.mechanics.leapfrog`): the state is the
displacement ``q = p − p0`` and the velocity, stored by component and grid slot
(:func:`~skinhil.model.mechanics.leapfrog.strip_layout`), and each force pass walks the
springs strip by strip: the springs of one kind join masses a constant number of slots apart
and share their rest vector ``L0·e0``, so a strip reads ``d = L0·e0 + q_j − q_i`` from
contiguous slices and the compiler vectorises it. With ``u = 1/|d|`` the force on ``i`` is

    f_s e = (k − (k L0 − T)·u + c·(dᵀ(v_j − v_i))·u²) · d

(the formula above, ``e = d·u``): one square root and one division per spring, nothing else
per spring that the rest directions do not fix. A spring of zero length pushes nothing (its
``d`` is 0). The net force at rest (the preload) is this pass's own at ``q = 0``,
so rest stays exactly at rest. Each RK4 stage is one pass over the strips and one over the
bands of moving slots, which also accumulates the RK4 sum, so a step holds no per-stage
arrays. State components below :data:`~skinhil.model.mechanics.leapfrog.TINY` (1e-150 m or
m/s) are flushed to zero when the step ends: subnormals are ~100x slower on x86, and a
formulation in absolute positions (~1e-3 m) would not resolve 1e-19 m anyway. The
results are a per-spring formulation's (absolute positions, ``e = d/L``, forces scattered
spring by spring) to rounding: tests/test_core_geometric_kernel.py pins them to within
1e-11 of the peak force; the strips are the faster (benchmarks/bench_size.py, ``mech``
column).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from skinhil.model.geometry import Mesh
from skinhil.model.mechanics.leapfrog import (
    TINY,
    scatter_strip,
    strip_layout,
    to_slots,
    write_readouts,
)
from skinhil.model.mechanics.linear import spring_frames
from skinhil.model.mechanics.readout import Readout, length_signal

RK4_STABILITY_RADIUS = 2.5
"""|λ|·dt bound used for RK4 (its real-axis limit is 2.785, imaginary-axis 2.828)."""

TINY_F64 = TINY[np.dtype(np.float64)]
"""State components below this (m, m/s) are flushed to zero when a step ends."""

LANES = 8
"""Each strip's force loop runs over a multiple of this many pairs (the vector lanes of
double precision at 512 bits), so that no pair of it runs in the compiler's scalar loop."""

JOIN_GAP = 16
"""Strips of one kind are joined across at most this many pairs of fixed masses
(:func:`~skinhil.model.mechanics.leapfrog.join_runs`): a strip's own overhead costs about
what 20 pairs do, so at 6x6 the two layers' strips of a kind become one, which steps
faster (benchmarks/bench_size.py, ``mech`` column)."""

SHORTEST_SQUARED = 1e-300
"""|d|² is taken at least this (m²): a spring of zero length then has a finite ``u`` and,
its ``d`` being 0, pushes nothing."""

class GeometricOperands(NamedTuple):
    """What the compiled RK4 step reads (:attr:`GeometricMechanics.operands`): arrays
    updated in place, double precision, by component and slot; the slots extend
    :data:`LANES` past the grid's (never moving)."""

    strips: np.ndarray
    """The strip table (:func:`~skinhil.model.mechanics.leapfrog.join_runs`)."""
    reach: np.ndarray
    """Each strip's length rounded up to :data:`LANES`."""
    plan: np.ndarray
    """The readout plan (:class:`~skinhil.model.mechanics.leapfrog.StripLayout`)."""
    run_e: np.ndarray
    """Each strip's rest unit vector (n_strips, 3)."""
    run_l0: np.ndarray
    """Each strip's rest length (m)."""
    still: np.ndarray
    """The springs between fixed masses: they read 0."""
    length: bool
    """Whether the readout is the length change (else the axial projection)."""
    k: float
    """Spring stiffness (N/m)."""
    c: float
    """Damping (N·s/m)."""
    t: float
    """Baseline tension (N)."""
    span: np.ndarray
    """The span of moving slots (first, end)."""
    inv_m: np.ndarray
    """1/m per slot (1/kg; 0 where fixed)."""
    preload: np.ndarray
    """The springs' net force at rest (3, n_slots) N."""
    slots: np.ndarray
    """Each mass's slot (:func:`~skinhil.model.mechanics.leapfrog.grid_slots`)."""
    q: np.ndarray
    """Displacement (3, n_slots) m."""
    v: np.ndarray
    """Velocity (3, n_slots) m/s."""
    qs: np.ndarray
    """Scratch: a stage's displacement (m)."""
    vs: np.ndarray
    """Scratch: a stage's velocity (m/s)."""
    sq: np.ndarray
    """Scratch: the RK4 sum of q' (m/s)."""
    sv: np.ndarray
    """Scratch: the RK4 sum of v' (m/s²)."""
    net: np.ndarray
    """Scratch: the springs' net force (3, n_slots) N."""
    signals: np.ndarray
    """Scratch: the readouts (n_strips, longest reach) N."""
    scratch: np.ndarray
    """Scratch: a strip's forces (3, longest reach) N."""


@numba.njit(inline="always", fastmath=True)
def _pull(dx: float, dy: float, dz: float, rate: float, k: float, c: float,
          pull: float) -> tuple[float, float]:  # pragma: no cover - compiled
    # (f_s/L, 1/L) of a spring along d (m) with dᵀ(v_j − v_i) = rate (m²/s), pull = k L0 − T
    u = 1.0 / math.sqrt(max(dx * dx + dy * dy + dz * dz, SHORTEST_SQUARED))
    return k - pull * u + c * rate * u * u, u


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def strip_forces(q: np.ndarray, v: np.ndarray, out: np.ndarray, strips: np.ndarray,
                 reach: np.ndarray, run_e: np.ndarray, run_l0: np.ndarray, k: float, c: float,
                 t: float, scratch: np.ndarray, signals: np.ndarray, readout: bool,
                 length: bool) -> None:  # pragma: no cover - compiled
    """The springs' net force (N) on every slot into ``out`` (3, n_slots) from the
    displacements ``q`` (m) and velocities ``v`` (m/s), (3, n_slots) each (module
    docstring); with ``readout`` also each strip's readouts (the length change if
    ``length``, else the axial projection; N) into ``signals``. Strip ``r`` is computed
    over ``reach[r]`` >= its length pairs (a whole number of vector lanes: the pairs past
    its end are computed, never added), so the arrays extend that far; ``scratch`` (3,
    longest reach)."""
    out[:] = 0.0
    qx, qy, qz = q[0], q[1], q[2]
    vx, vy, vz = v[0], v[1], v[2]
    fx_s, fy_s, fz_s = scratch[0], scratch[1], scratch[2]
    for r in range(strips.shape[0]):
        i0, j0, n, nn = strips[r, 0], strips[r, 1], strips[r, 2], reach[r]
        l0 = run_l0[r]
        ex, ey, ez = run_e[r, 0], run_e[r, 1], run_e[r, 2]
        bx, by, bz = l0 * ex, l0 * ey, l0 * ez
        pull = k * l0 - t
        qxi, qyi, qzi = qx[i0:i0 + nn], qy[i0:i0 + nn], qz[i0:i0 + nn]
        qxj, qyj, qzj = qx[j0:j0 + nn], qy[j0:j0 + nn], qz[j0:j0 + nn]
        vxi, vyi, vzi = vx[i0:i0 + nn], vy[i0:i0 + nn], vz[i0:i0 + nn]
        vxj, vyj, vzj = vx[j0:j0 + nn], vy[j0:j0 + nn], vz[j0:j0 + nn]
        if readout:  # the same pass, and the readout of its d − L0·e
            sig = signals[r]
            kex, key, kez = k * ex, k * ey, k * ez
            for m in range(nn):
                ux = qxj[m] - qxi[m]
                uy = qyj[m] - qyi[m]
                uz = qzj[m] - qzi[m]
                dx, dy, dz = bx + ux, by + uy, bz + uz
                g, u = _pull(dx, dy, dz, dx * (vxj[m] - vxi[m]) + dy * (vyj[m] - vyi[m])
                             + dz * (vzj[m] - vzi[m]), k, c, pull)
                fx_s[m] = g * dx
                fy_s[m] = g * dy
                fz_s[m] = g * dz
                proj = kex * ux + key * uy + kez * uz
                if length:
                    sig[m] = length_signal(proj, ux * ux + uy * uy + uz * uz,
                                           (dx * dx + dy * dy + dz * dz) * u, k, l0)
                else:
                    sig[m] = proj
        else:
            for m in range(nn):
                dx = bx + (qxj[m] - qxi[m])
                dy = by + (qyj[m] - qyi[m])
                dz = bz + (qzj[m] - qzi[m])
                g, u = _pull(dx, dy, dz, dx * (vxj[m] - vxi[m]) + dy * (vyj[m] - vyi[m])
                             + dz * (vzj[m] - vzi[m]), k, c, pull)
                fx_s[m] = g * dx
                fy_s[m] = g * dy
                fz_s[m] = g * dz
        scatter_strip(out, scratch, i0, j0, n)


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def rk4_step(fs: np.ndarray, row: np.ndarray, dt: float,
             ops: GeometricOperands) -> None:  # pragma: no cover - compiled
    """One step: the external forces ``fs`` (3, n_slots) N by component and slot, held over
    ``dt`` (s) → ``row`` (n_springs,) N, the readouts at the step's start; ``ops`` after
    ``dt`` (:attr:`GeometricMechanics.operands`). Contiguous rows keep the loops
    vectorised."""
    q, v, qs, vs, sq, sv, net = ops.q, ops.v, ops.qs, ops.vs, ops.sq, ops.sv, ops.net
    strips, reach, run_e, run_l0 = ops.strips, ops.reach, ops.run_e, ops.run_l0
    k, c, t, length, signals, scratch = ops.k, ops.c, ops.t, ops.length, ops.signals, \
        ops.scratch
    preload, inv_m = ops.preload, ops.inv_m
    half_dt = 0.5 * dt
    sixth_dt = dt / 6.0
    m0, m1 = ops.span[0], ops.span[1]
    width = m1 - m0
    for s in ops.still:  # between fixed masses: never stretched
        row[s] = 0.0
    for stage in range(4):
        if stage == 0:  # the state at the step's start: its readouts too
            strip_forces(q, v, net, strips, reach, run_e, run_l0, k, c, t, scratch,
                         signals, True, length)
            write_readouts(row, signals, ops.plan)
        else:
            strip_forces(qs, vs, net, strips, reach, run_e, run_l0, k, c, t, scratch,
                         signals, False, length)
        h = dt if stage == 2 else half_dt
        for a in range(3):  # the moving slots' span (a fixed one's 1/m is 0)
            qa, va = q[a, m0:m1], v[a, m0:m1]
            qsa, vsa = qs[a, m0:m1], vs[a, m0:m1]
            sqa, sva = sq[a, m0:m1], sv[a, m0:m1]
            na, pa, fa = net[a, m0:m1], preload[a, m0:m1], fs[a, m0:m1]
            ima = inv_m[m0:m1]
            if stage == 0:  # k1; the sums start
                for m in range(width):
                    acc = (na[m] - pa[m] + fa[m]) * ima[m]
                    vel = va[m]
                    sqa[m] = vel
                    sva[m] = acc
                    qsa[m] = qa[m] + h * vel
                    vsa[m] = vel + h * acc
            elif stage < 3:  # k2, k3: twice into the sums
                for m in range(width):
                    acc = (na[m] - pa[m] + fa[m]) * ima[m]
                    vel = vsa[m]
                    sqa[m] += 2.0 * vel
                    sva[m] += 2.0 * acc
                    qsa[m] = qa[m] + h * vel
                    vsa[m] = va[m] + h * acc
            else:  # k4: the step, dt/6 (k1 + 2 k2 + 2 k3 + k4)
                for m in range(width):
                    acc = (na[m] - pa[m] + fa[m]) * ima[m]
                    qm = qa[m] + sixth_dt * (sqa[m] + vsa[m])
                    vm = va[m] + sixth_dt * (sva[m] + acc)
                    qa[m] = qm if abs(qm) > TINY_F64 else 0.0
                    va[m] = vm if abs(vm) > TINY_F64 else 0.0


@numba.njit(cache=True, nogil=True)
def rk4_kernel(forces: np.ndarray, out: np.ndarray, dt: float,
               operands: tuple) -> None:  # pragma: no cover - compiled
    """forces (n, 3, n_slots) N by component and slot (:meth:`GeometricMechanics.by_slot`),
    each held over a step of ``dt`` (s) → out (n, n_springs) N, the readouts at the start of
    each step (:func:`rk4_step` step by step); ``operands`` is
    ``tuple(GeometricMechanics.operands)``."""
    ops = GeometricOperands(*operands)
    for step in range(forces.shape[0]):
        rk4_step(forces[step], out[step], dt, ops)


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
        """Every mass's rest position (n_masses, 3) m."""
        self.springs = np.ascontiguousarray(mesh.springs)
        e, self.rest_lengths = spring_frames(mesh)
        self.k, self.c, self.t = stiffness_n_per_m, damping_n_s_per_m, tension_n
        self.inv_m = 1.0 / mass_kg
        self.mass_kg = mass_kg
        self.dt_s = dt_s
        self.free = np.ascontiguousarray(mesh.free)
        self.n_springs = int(self.springs.shape[0])
        layout = strip_layout(mesh, e, tension_n / self.rest_lengths, self.rest_lengths,
                              JOIN_GAP)
        self.slots = layout.slots
        """Each mass's slot in :attr:`state`
        (:func:`~skinhil.model.mechanics.leapfrog.grid_slots`)."""
        strips = layout.strips
        reach = -(-strips[:, 2] // LANES) * LANES
        n_slots = layout.fixed.size + LANES  # the strips' reach: the slots past stay 0
        self.state = np.zeros((2, 3, n_slots))
        """Displacement q (m) and velocity v (m/s) by component and slot; updated in place."""
        moving = layout.moving
        span = (np.array([moving[0, 0], moving[-1, 0] + moving[-1, 1]], dtype=np.int64)
                if len(moving) else np.zeros(2, dtype=np.int64))
        longest = int(reach.max(initial=LANES))
        scratch = np.zeros((3, longest))
        signals = np.zeros((len(strips), longest))
        preload = np.zeros((3, n_slots))
        strip_forces(self.state[0], self.state[1], preload, strips, reach, layout.run_e,
                     layout.run_l0, float(self.k), float(self.c), float(self.t), scratch,
                     signals, False, True)
        self.operands = GeometricOperands(
            strips=strips, reach=reach, plan=layout.plan, run_e=layout.run_e,
            run_l0=layout.run_l0, still=layout.still, length=readout == "length",
            k=float(self.k), c=float(self.c), t=float(self.t), span=span,
            inv_m=np.append(np.where(layout.fixed, 0.0, self.inv_m), np.zeros(LANES)),
            preload=preload, slots=self.slots, q=self.state[0], v=self.state[1],
            qs=np.zeros((3, n_slots)), vs=np.zeros((3, n_slots)), sq=np.zeros((3, n_slots)),
            sv=np.zeros((3, n_slots)), net=np.zeros((3, n_slots)), signals=signals,
            scratch=scratch)
        """What the compiled step reads (:class:`GeometricOperands`); a kernel called from
        Python takes ``tuple(operands)`` (:meth:`~skinhil.model.neurons.NeuronPopulation.
        kernel_operands` says why)."""
        self.kernel_tuple = tuple(self.operands)
        """:attr:`operands` as the kernels called from Python take them."""

    @property
    def preload(self) -> np.ndarray:
        """The springs' net force at rest on every mass (n_masses, 3) N, held by the
        surrounding tissue (module docstring)."""
        return self.operands.preload[:, self.slots].T.copy()

    def by_slot(self, forces_n: np.ndarray) -> np.ndarray:
        """External forces (n, n_masses, 3) N as :func:`rk4_kernel` reads them: (n, 3,
        n_slots), by component and slot."""
        return to_slots(forces_n, self.slots, self.state.shape[2], np.float64)

    def reset(self) -> None:
        """Back to rest: rest positions, zero velocity."""
        self.state[:] = 0.0

    def displacement_m(self) -> np.ndarray:
        """Every mass's displacement from rest now (n_masses, 3) m; fixed masses 0."""
        return self.state[0][:, self.slots].T.copy()

    @property
    def p(self) -> np.ndarray:
        """Every mass's position now (n_masses, 3) m."""
        return self.rest_positions + self.displacement_m()

    @property
    def v(self) -> np.ndarray:
        """Every mass's velocity now (n_masses, 3) m/s."""
        return self.state[1][:, self.slots].T.copy()

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """Step ``len(forces_n)`` steps; ``forces_n`` is (n, n_masses, 3) N; returns
        (n, n_springs) N.

        Row ``j`` of the result is the spring forces at the start of step ``j``; input ``j`` is
        then held over the step.
        """
        forces = self.by_slot(forces_n)
        out = np.empty((forces.shape[0], self.n_springs))
        rk4_kernel(forces, out, self.dt_s, self.kernel_tuple)
        return out

    def energy_j(self) -> float:
        """Mechanical energy (J): kinetic + Σ ½k(L − L0)² + T(L − L0) + preload·(p − p0)."""
        p, v = self.p, self.v
        d = p[self.springs[:, 1]] - p[self.springs[:, 0]]
        ext = np.linalg.norm(d, axis=1) - self.rest_lengths
        kinetic = 0.5 * self.mass_kg * float(np.sum(v[self.free] ** 2))
        elastic = float(np.sum(0.5 * self.k * ext**2 + self.t * ext))
        moved = (p - self.rest_positions)[self.free]
        return kinetic + elastic + float(np.sum(self.preload[self.free] * moved))
