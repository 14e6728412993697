"""The ``linear`` mechanics for large meshes: a leapfrog stepper of cost O(springs) per step.

Same equations as :mod:`skinhil.model.mechanics.linear` (``M q'' + C q' + K q = f`` on the free
masses, axial springs and dampers plus the geometric stiffness ``T/L (I − e eᵀ)`` of a
baseline tension), never assembled: each step makes one pass over the springs, reading the
displacements and velocities of its two masses and adding its force to both, so a step costs
O(springs) time and memory where the exact ZOH of :mod:`skinhil.model.mechanics.linear` costs
O(dof²). The pass goes run by run (:func:`spring_runs`: the springs of one kind along a row
of the grid), each run reading and updating its masses as contiguous slices, so the compiler
vectorises it, faster than spring by spring (benchmarks/bench_size.py). Only what can
move is stepped: the free masses (:func:`moving_bands`) and the runs with a free mass; the
springs between fixed masses (all of layer 3's, the edges') read 0. The model uses it
above ``EXACT_MAX_FREE_DOFS`` free degrees of freedom (:mod:`skinhil.model.skin`).

A row's run is short (32-33 springs at 34x34), shorter than one pass of the compiler's
vector loop (16 single-precision lanes, unrolled), which then ran it a float at a time. So
the state is kept in grid slots (:func:`grid_slots`: every layer with the top layer's row
stride, the lower layers' rows padded with unused slots that never move), where the springs
of one kind join masses a constant number of slots apart in every row, and the runs of a
kind are joined across the fixed pairs between rows into strips of ~1,100
(:func:`join_runs`: 14 strips at 34x34 instead of 382 runs); the readouts go out to the
springs' order by a plan (:func:`readout_plan`), the moving masses in one band per layer
(:func:`moving_bands`): each of the three shortens the step (benchmarks/bench_size.py,
``mech`` column).

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

Precision: the state, the input and the spring forces are single precision
(:data:`DTYPE`), which halves the memory the step streams through and doubles the lanes of
its vector instructions (benchmarks/bench_size.py against ``dtype=np.float64``). Error
budget: single precision rounds at 6e-8 of a value; the scheme's own error is 1.3e-3 of the
peak force; measured, the forces stay within 4e-7 of the peak of the double-precision
reference (``dtype=np.float64``, the same code), and the spikes are the reference's: not one
differs noise-free on the paper's stimuli and the direction conditions at 16x16 and 34x34
(1,787 and 1,790 spikes), nor at 10 dB over 2 s of the default schedule at 34x34 (32,085
spikes); tests/test_core_leapfrog.py pins it. The heavily damped scheme forgets rounding
within a few steps (γ·h ≈ 0.4), so it does not accumulate.

The sensor signal of spring ``s`` at the start of each step is its length change
``k (|L0 e + q_j − q_i| − L0)`` (N) or, with ``readout="axial"``, ``k eᵀ(q_j − q_i)``
(:mod:`skinhil.model.mechanics.readout`), as in the exact stepper: computed in the run loop from
the displacements it reads anyway, with the run's rest length a scalar (the springs of a run
share it), so the loop stays vectorised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np
from scipy.sparse.linalg import eigsh

from skinhil.model.geometry import Mesh, mass_position
from skinhil.model.mechanics.linear import assemble, free_block, spring_frames
from skinhil.model.mechanics.readout import Readout, spring_signal

STABILITY_BOUND = 0.9
"""Substeps are chosen so that ``γ·h + (ω·h)²/4`` stays below this (the scheme's limit is 1)."""
ACCURACY_OMEGA_H = 0.25
"""... and so that ``ω·h`` stays below this: the fastest mode's phase error per period is then
below ``(ω·h)²/24`` ≈ 0.3 %."""

TINY = {np.dtype(np.float64): 1e-150, np.dtype(np.float32): 1e-30}
"""Per precision: state components below this are flushed to zero (subnormals are ~100x
slower on x86; 1e-30 m or m/s is nothing for a skin)."""

DTYPE: type[np.floating] = np.float32
"""The leapfrog's precision: state, input and spring forces in single precision (module
docstring, "Precision"); ``LeapfrogMechanics(dtype=np.float64)`` is the reference."""

SAME_DIRECTION = 1e-12
"""Springs whose rest unit vectors differ by at most this (per component) share a run's
direction (the rest positions of a regular mesh give the same direction to within rounding)."""

RUN_FIELDS = 5
"""Columns of a run table: first spring, spring stride, first mass i, first mass j, length."""

MAX_GAP = 4
""":func:`join_runs` bridges at most this many pairs of fixed masses between two runs."""

class LeapfrogOperands(NamedTuple):
    """What the compiled leapfrog step reads (:attr:`LeapfrogMechanics.operands`): arrays
    updated in place, the state stored by component and slot (3, n_slots,
    :func:`grid_slots`), the reals in the stepper's precision (:data:`DTYPE`)."""

    strips: np.ndarray
    """The strip table (:func:`join_runs`)."""
    plan: np.ndarray
    """The readout plan (:func:`readout_plan`)."""
    run_e: np.ndarray
    """Each strip's rest unit vector (n_strips, 3)."""
    run_tl: np.ndarray
    """Each strip's T/L (N/m)."""
    run_l0: np.ndarray
    """Each strip's rest length (m)."""
    still: np.ndarray
    """The springs between fixed masses: they read 0."""
    length: bool
    """Whether the readout is the length change (else the axial projection)."""
    k: np.floating
    """Spring stiffness (N/m)."""
    c: np.floating
    """Damping (N·s/m)."""
    moving: np.ndarray
    """The bands of slots stepped (:func:`moving_bands`)."""
    inv_m: np.ndarray
    """1/m per slot (1/kg; 0 where fixed)."""
    tiny: np.floating
    """State components below this are flushed to zero (:data:`TINY`)."""
    slots: np.ndarray
    """Each mass's slot (:func:`grid_slots`)."""
    substeps: int
    """Leapfrog steps per step (:func:`substeps_for`)."""
    q: np.ndarray
    """Displacement (m)."""
    v: np.ndarray
    """Velocity at the half step (m/s)."""
    w: np.ndarray
    """Velocity at the step's start (m/s)."""
    f_prev: np.ndarray
    """The last input (N)."""
    acc: np.ndarray
    """Scratch: the springs' net force (N), (3, n_slots)."""
    signals: np.ndarray
    """Scratch: the readouts (n_strips, longest strip)."""
    scratch: np.ndarray
    """Scratch: the forces of a strip (3, longest strip)."""


def grid_slots(mesh: Mesh) -> np.ndarray:
    """Each mass's slot (int64) in the stepper's state: layer ``L``, row ``r``, column ``c``
    at ``L·rows·cols + r·cols + c`` for the top layer's ``rows x cols``, so every layer has
    the top layer's row stride (the lower layers' rows end in unused slots, held fixed).

    Then the springs of one kind join masses a constant number of slots apart in every row,
    between layers too (in mass numbers a lower layer's rows are one or two shorter), and
    :func:`join_runs` makes one strip of them."""
    rows, cols = mesh.size
    where = [mass_position(i, mesh.size) for i in range(mesh.positions.shape[0])]
    return np.array([(layer * rows + r) * cols + c for layer, r, c in where], dtype=np.int64)


def moving_bands(fixed: np.ndarray) -> np.ndarray:
    """The slots the kernel steps, as (first, count) rows (int64): from each free slot to the
    next across at most :data:`MAX_GAP` fixed ones, i.e. on a grid one band per layer 1 and
    2 from its first free mass to its last, the fixed edge masses between its rows included
    (their 1/m is 0 in the kernel: they never move) so that the loop runs long; layer 3,
    all fixed, is never stepped."""
    free = np.flatnonzero(~np.asarray(fixed, dtype=bool))
    if free.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    starts = np.flatnonzero(np.diff(free, prepend=free[0] - MAX_GAP - 2) > MAX_GAP + 1)
    ends = np.append(free[starts[1:] - 1], free[-1])
    return np.stack([free[starts], ends - free[starts] + 1], axis=1).astype(np.int64)


def same_kind(e: np.ndarray, t_over_l: np.ndarray, rest: np.ndarray, a: int, b: int) -> bool:
    """Whether springs (or runs) ``a`` and ``b`` share their unit vector ``e`` (to
    :data:`SAME_DIRECTION` per component), T/L and rest length (to it relatively)."""
    return bool(np.abs(e[b] - e[a]).max() <= SAME_DIRECTION
                and abs(t_over_l[b] - t_over_l[a]) <= SAME_DIRECTION * abs(t_over_l[a])
                and abs(rest[b] - rest[a]) <= SAME_DIRECTION * rest[a])


def spring_runs(springs: np.ndarray, e: np.ndarray, t_over_l: np.ndarray,
                rest: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Group the springs into runs for :func:`leapfrog_kernel`: spring ``s0 + t·ds`` of a
    run joins masses ``i0 + t`` and ``j0 + t`` (t = 0 .. length − 1) along one direction
    ``e`` with one ``T/L`` and one rest length (m). On a grid the springs of one kind along
    a row (and the column springs of a whole layer) form one run, so the kernel reads the
    masses of a run as contiguous slices, which the compiler turns into vector instructions,
    and scatters the forces the same way. Any spring list works: a spring with no such
    neighbour is a run of one.

    Returns the (n_runs, 5) int64 table (s0, ds, i0, j0, length), each run's e (n_runs, 3),
    T/L (n_runs,) in N/m and rest length (n_runs,) in m.
    """
    where = {(int(i), int(j)): s for s, (i, j) in enumerate(springs)}
    taken = np.zeros(len(springs), dtype=bool)
    runs = []
    for s, (i, j) in enumerate(springs):
        if taken[s]:
            continue
        taken[s] = True
        last, stride, length = s, 0, 1
        while True:
            nxt = where.get((int(i) + length, int(j) + length))
            if (nxt is None or taken[nxt] or nxt <= last or (stride and nxt - last != stride)
                    or not same_kind(e, t_over_l, rest, s, nxt)):
                break
            stride, last = nxt - last, nxt
            taken[nxt] = True
            length += 1
        runs.append((s, stride or 1, int(i), int(j), length))
    table = np.array(runs, dtype=np.int64).reshape(-1, RUN_FIELDS)
    first = table[:, 0]
    return (table, np.ascontiguousarray(e[first]), np.ascontiguousarray(t_over_l[first]),
            np.ascontiguousarray(rest[first]))


def join_runs(runs: np.ndarray, fixed: np.ndarray, kinds: np.ndarray,
              max_gap: int = MAX_GAP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Join the runs of one kind (equal ``kinds``: direction, T/L and rest length) that
    continue each other across at most ``max_gap`` pairs of fixed masses into strips.

    The springs of one kind along a grid row are a run of 32 or 33 at 34x34, too short for
    the compiler's vector loops (16 single-precision lanes, unrolled); the next row's run of
    the same kind starts a mass or two further on, past a pair of fixed edge masses, which
    never move: a "spring" between them would read zero and push nothing. So a strip steps
    the runs and the pairs between them as one run of ~1,100 (the kernel computes the pairs'
    zero forces and writes no readout for them).

    Returns the (n_strips, 5) int64 table (i0, j0, length, first segment, segments), the
    (n_segments, 4) int64 segments (offset in the strip, first spring, spring stride,
    length) whose readouts go out, and for each strip the index of its first run (for its
    e, T/L and rest length).
    """
    order = np.lexsort((runs[:, 2], runs[:, 3] - runs[:, 2], kinds))
    strips: list[list[int]] = []
    segments: list[tuple[int, int, int, int]] = []
    first_run: list[int] = []
    for r in order:
        s0, ds, i0, j0, n = (int(x) for x in runs[r])
        if strips:
            si0, sj0, sn, _, _ = strips[-1]
            gap = i0 - (si0 + sn)
            if (kinds[r] == kinds[first_run[-1]] and j0 - i0 == sj0 - si0
                    and 0 <= gap <= max_gap and fixed[si0 + sn:i0].all()
                    and fixed[sj0 + sn:j0].all()):
                segments.append((sn + gap, s0, ds, n))
                strips[-1][2] = sn + gap + n
                strips[-1][4] += 1
                continue
        strips.append([i0, j0, n, len(segments), 1])
        segments.append((0, s0, ds, n))
        first_run.append(int(r))
    return (np.array(strips, dtype=np.int64).reshape(-1, 5),
            np.array(segments, dtype=np.int64).reshape(-1, 4), np.array(first_run, np.int64))


def run_kinds(run_e: np.ndarray, run_tl: np.ndarray, run_l0: np.ndarray) -> np.ndarray:
    """A label per run, equal for runs of the same kind (:func:`same_kind`)."""
    firsts: list[int] = []  # the first run of each kind
    labels = np.empty(len(run_e), dtype=np.int64)
    for r in range(len(run_e)):
        label = next((k for k, f in enumerate(firsts)
                      if same_kind(run_e, run_tl, run_l0, f, r)), len(firsts))
        if label == len(firsts):
            firsts.append(r)
        labels[r] = label
    return labels


PLAN_FIELDS = 12
"""Columns of a readout plan: first spring, spring stride, members (1 or 4), length, then
each member's strip and offset in it (-1 where unused)."""


def readout_plan(strips: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """How the kernel writes the strips' readouts in spring order: one row per segment of a
    run (:func:`join_runs`), except that four segments of stride 4 that interleave (springs
    ``s0 + 4t + k``: the four springs a lower mass sends up or down, numbered together) go
    as one row, which the compiler writes as contiguous vectors; a
    stride-4 segment alone would be written a float at a time.

    Returns the (n_rows, :data:`PLAN_FIELDS`) int64 plan."""
    strip_of = np.repeat(np.arange(len(strips)), strips[:, 4])
    first = {(int(s0), int(ds), int(m)): g for g, (_, s0, ds, m) in enumerate(segments)}
    done = np.zeros(len(segments), dtype=bool)
    plan = []
    for g in np.argsort(segments[:, 1], kind="stable"):  # by first spring
        _, s0, ds, m = segments[g]
        if done[g]:
            continue
        mates = [first.get((int(s0) + k, int(ds), int(m))) for k in range(1, 4)]
        group = [g]
        if ds == 4 and all(p is not None and not done[p] for p in mates):
            group += [int(p) for p in mates if p is not None]
        members = [(strip_of[x], segments[x, 0]) for x in group]
        members += [(-1, -1)] * (4 - len(members))
        plan.append((s0, ds, len(group), m, *(v for pair in members for v in pair)))
        done[group] = True
    return np.array(plan, dtype=np.int64).reshape(-1, PLAN_FIELDS)


@dataclass(frozen=True)
class StripLayout:
    """Where a strip stepper (:func:`leapfrog_kernel`, the geometric mechanics'
    :func:`skinhil.model.mechanics.geometric.rk4_kernel`) keeps each mass and how it walks
    the springs (:func:`strip_layout`)."""

    slots: np.ndarray
    """Each mass's slot (:func:`grid_slots`)."""
    fixed: np.ndarray
    """(n_slots,) bool: the slots that never move (fixed masses, unused slots)."""
    strips: np.ndarray
    """The strip table (:func:`join_runs`) of the runs with a free mass."""
    plan: np.ndarray
    """The readout plan (:func:`readout_plan`)."""
    run_e: np.ndarray
    """Each strip's rest unit vector (n_strips, 3)."""
    run_tl: np.ndarray
    """Each strip's T/L (N/m)."""
    run_l0: np.ndarray
    """Each strip's rest length (m)."""
    still: np.ndarray
    """The springs between fixed masses (int64): they never stretch and read 0."""
    moving: np.ndarray
    """The bands of slots stepped (:func:`moving_bands`)."""


def strip_layout(mesh: Mesh, e: np.ndarray, t_over_l: np.ndarray, length: np.ndarray,
                 max_gap: int = MAX_GAP) -> StripLayout:
    """The strips of ``mesh`` for springs of rest unit vectors ``e`` (n_springs, 3), T/L
    (N/m) and rest lengths (m): runs (:func:`spring_runs`) on the grid slots, those between
    fixed masses only set aside (never stretched), the rest joined into strips across at
    most ``max_gap`` fixed pairs (:func:`join_runs`), with their readout plan and the bands
    of moving slots."""
    slots = grid_slots(mesh)
    n_slots = 3 * mesh.size[0] * mesh.size[1]
    fixed = np.ones(n_slots, dtype=bool)  # the unused slots never move
    fixed[slots] = mesh.fixed
    runs, run_e, run_tl, run_l0 = spring_runs(slots[mesh.springs], e, t_over_l, length)
    # a run between fixed masses only is never stretched: its springs' force stays 0
    live = np.array([not (fixed[i0:i0 + n].all() and fixed[j0:j0 + n].all())
                     for _, _, i0, j0, n in runs], dtype=bool)
    still = np.concatenate([s0 + ds * np.arange(n) for s0, ds, _, _, n in runs[~live]]
                           + [np.zeros(0, dtype=np.int64)]).astype(np.int64)
    runs, run_e, run_tl, run_l0 = runs[live], run_e[live], run_tl[live], run_l0[live]
    strips, segments, first = join_runs(runs, fixed, run_kinds(run_e, run_tl, run_l0),
                                        max_gap)
    return StripLayout(slots, fixed, strips, readout_plan(strips, segments), run_e[first],
                       run_tl[first], run_l0[first], still, moving_bands(fixed))


def to_slots(forces_n: np.ndarray, slots: np.ndarray, n_slots: int,
             dtype: np.dtype | type[np.floating]) -> np.ndarray:
    """External forces (n, n_masses, 3) N as the strip kernels read them: (n, 3, n_slots),
    by component and slot (``slots``, :func:`grid_slots`), in ``dtype``."""
    f = np.asarray(forces_n)
    out = np.zeros((f.shape[0], 3, n_slots), dtype=dtype)
    out[:, :, slots] = f.transpose(0, 2, 1)
    return out


@numba.njit(inline="always")
def write_readouts(row: np.ndarray, signals: np.ndarray,
                    plan: np.ndarray) -> None:  # pragma: no cover - compiled
    # the strips' readouts (signals, by strip) into the spring-ordered row, by the plan
    for p in range(plan.shape[0]):
        s0, ds, members, m = plan[p, 0], plan[p, 1], plan[p, 2], plan[p, 3]
        a = signals[plan[p, 4], plan[p, 5]:plan[p, 5] + m]
        if members == 4:  # four interleaved runs: contiguous in the row
            b = signals[plan[p, 6], plan[p, 7]:plan[p, 7] + m]
            c = signals[plan[p, 8], plan[p, 9]:plan[p, 9] + m]
            d = signals[plan[p, 10], plan[p, 11]:plan[p, 11] + m]
            dest = row[s0:s0 + 4 * m]
            for t in range(m):
                dest[4 * t] = a[t]
                dest[4 * t + 1] = b[t]
                dest[4 * t + 2] = c[t]
                dest[4 * t + 3] = d[t]
        elif ds == 1:  # a slice: the compiler vectorises the copy
            dest = row[s0:s0 + m]
            for t in range(m):
                dest[t] = a[t]
        else:
            for t in range(m):
                row[s0 + ds * t] = a[t]


@numba.njit(inline="always")
def scatter_strip(acc: np.ndarray, forces: np.ndarray, i0: int, j0: int,
                  n: int) -> None:  # pragma: no cover - compiled
    """Add a strip's spring forces ``forces`` (3, >= n) N, those on its masses ``i``, to the
    net force ``acc`` (3, n_slots) on its slots ``i0 ..`` and minus them on ``j0 ..``: two
    loops, since the masses i of a strip may be its masses j."""
    gxi, gyi, gzi = acc[0, i0:i0 + n], acc[1, i0:i0 + n], acc[2, i0:i0 + n]
    gxj, gyj, gzj = acc[0, j0:j0 + n], acc[1, j0:j0 + n], acc[2, j0:j0 + n]
    fx_s, fy_s, fz_s = forces[0], forces[1], forces[2]
    for m in range(n):
        gxi[m] += fx_s[m]
        gyi[m] += fy_s[m]
        gzi[m] += fz_s[m]
    for m in range(n):
        gxj[m] -= fx_s[m]
        gyj[m] -= fy_s[m]
        gzj[m] -= fz_s[m]


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def leapfrog_step(fs: np.ndarray, row: np.ndarray, dt: float,
                  ops: LeapfrogOperands) -> None:  # pragma: no cover - compiled
    """One step of ``dt`` (s) in ``ops.substeps`` leapfrog steps: the external forces ``fs``
    (3, n_slots) N by component and slot, held over it → ``row`` (n_springs,) N, the
    readouts at the step's start. Every real is in the state's precision: no float64
    constant promotes single-precision arithmetic."""
    q, v, w, f_prev, acc = ops.q, ops.v, ops.w, ops.f_prev, ops.acc
    runs, run_e, run_tl, run_l0, signals = ops.strips, ops.run_e, ops.run_tl, ops.run_l0, \
        ops.signals
    k, c, length, moving, inv_m, tiny = ops.k, ops.c, ops.length, ops.moving, ops.inv_m, \
        ops.tiny
    substeps = ops.substeps
    real = q.dtype.type
    h = real(dt / substeps)
    half = real(0.5)
    half_h = real(0.5 * (dt / substeps))
    zero = real(0.0)
    qx, qy, qz = q[0], q[1], q[2]
    wx, wy, wz = w[0], w[1], w[2]
    scratch = ops.scratch
    fx_s, fy_s, fz_s = scratch[0], scratch[1], scratch[2]
    for s in ops.still:  # between fixed masses: never stretched
        row[s] = 0.0
    for sub in range(substeps):
        acc[:] = 0.0
        for r in range(runs.shape[0]):  # strip by strip
            i0, j0, n = runs[r, 0], runs[r, 1], runs[r, 2]
            sig_s = signals[r]
            ex, ey, ez, tl = run_e[r, 0], run_e[r, 1], run_e[r, 2], run_tl[r]
            kex, key, kez, l0 = k * ex, k * ey, k * ez, run_l0[r]
            qxi, qyi, qzi = qx[i0:i0 + n], qy[i0:i0 + n], qz[i0:i0 + n]
            qxj, qyj, qzj = qx[j0:j0 + n], qy[j0:j0 + n], qz[j0:j0 + n]
            wxi, wyi, wzi = wx[i0:i0 + n], wy[i0:i0 + n], wz[i0:i0 + n]
            wxj, wyj, wzj = wx[j0:j0 + n], wy[j0:j0 + n], wz[j0:j0 + n]
            for t in range(n):  # extension, its rate along e, the spring's force, readout
                dx = qxj[t] - qxi[t]
                dy = qyj[t] - qyi[t]
                dz = qzj[t] - qzi[t]
                ext = ex * dx + ey * dy + ez * dz
                rate = (ex * (wxj[t] - wxi[t]) + ey * (wyj[t] - wyi[t])
                        + ez * (wzj[t] - wzi[t]))
                sig_s[t] = spring_signal(kex, key, kez, dx, dy, dz, k, l0, length)
                ax = k * ext + c * rate - tl * ext  # axial, along e; tension across
                fx_s[t] = ax * ex + tl * dx
                fy_s[t] = ax * ey + tl * dy
                fz_s[t] = ax * ez + tl * dz
            scatter_strip(acc, scratch, i0, j0, n)
        if sub == 0:
            write_readouts(row, signals, ops.plan)
        for a in range(3):  # the bands of moving masses (a fixed one's 1/m is 0)
            for mr in range(moving.shape[0]):
                m0, nm = moving[mr, 0], moving[mr, 1]
                qa, va, wa = q[a, m0:m0 + nm], v[a, m0:m0 + nm], w[a, m0:m0 + nm]
                fa, ga, fsa = f_prev[a, m0:m0 + nm], acc[a, m0:m0 + nm], fs[a, m0:m0 + nm]
                ima = inv_m[m0:m0 + nm]
                for m in range(nm):
                    f_now = fsa[m]
                    am = (ga[m] + half * (fa[m] + f_now)) * ima[m]
                    fa[m] = f_now
                    vm = va[m] + h * am
                    qm = qa[m] + h * vm
                    wm = vm + half_h * am
                    va[m] = vm if abs(vm) > tiny else zero
                    qa[m] = qm if abs(qm) > tiny else zero
                    wa[m] = wm if abs(wm) > tiny else zero


@numba.njit(cache=True, nogil=True)
def leapfrog_kernel(forces: np.ndarray, out: np.ndarray, dt: float,
                    operands: tuple) -> None:  # pragma: no cover - compiled
    """forces (n, 3, n_slots) N, by component and slot (:meth:`LeapfrogMechanics.by_slot`),
    held per step of ``dt`` (s) → out (n, n_springs) N (:func:`leapfrog_step` step by
    step); ``operands`` is ``tuple(LeapfrogMechanics.operands)``."""
    ops = LeapfrogOperands(*operands)
    for step in range(forces.shape[0]):
        leapfrog_step(forces[step], out[step], dt, ops)


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
                 damping_n_s_per_m: float, tension_n: float, dt_s: float,
                 readout: Readout = "length", dtype: type[np.floating] = DTYPE) -> None:
        e, length = spring_frames(mesh)
        self.dtype = np.dtype(dtype)
        """Precision of the state, the input and the spring forces (:data:`DTYPE`)."""
        real = dtype
        self.readout = readout
        """What each spring reports (:mod:`skinhil.model.mechanics.readout`)."""
        n = mesh.positions.shape[0]
        self.dt_s = dt_s
        self.omega_max, self.gamma_max = fastest_rates(mesh, mass_kg, stiffness_n_per_m,
                                                       damping_n_s_per_m, tension_n)
        self.substeps = substeps_for(self.omega_max, self.gamma_max, dt_s)
        self.n_masses = n
        self.n_springs = mesh.springs.shape[0]
        layout = strip_layout(mesh, e, tension_n / length, length)
        self.slots = layout.slots
        """Each mass's slot in :attr:`state` (:func:`grid_slots`)."""
        n_slots, strips = layout.fixed.size, layout.strips
        self.state = np.zeros((4, 3, n_slots), dtype=self.dtype)
        """Displacement q (m), velocity v (m/s) at the half step and w at the step start,
        and the last input (N), by component and slot (:attr:`slots`); updated in place."""
        longest = int(strips[:, 2].max(initial=1))
        state = self.state
        self.operands = LeapfrogOperands(
            strips=strips, plan=layout.plan, run_e=layout.run_e.astype(self.dtype),
            run_tl=layout.run_tl.astype(self.dtype), run_l0=layout.run_l0.astype(self.dtype),
            still=layout.still, length=readout == "length", k=real(stiffness_n_per_m),
            c=real(damping_n_s_per_m), moving=layout.moving,
            inv_m=np.where(layout.fixed, 0.0, 1.0 / mass_kg).astype(self.dtype),
            tiny=real(TINY[self.dtype]), slots=self.slots, substeps=self.substeps,
            q=state[0], v=state[1], w=state[2], f_prev=state[3],
            acc=np.zeros((3, n_slots), dtype=self.dtype),
            signals=np.zeros((len(strips), longest), dtype=self.dtype),
            scratch=np.zeros((3, longest), dtype=self.dtype))
        """What the compiled step reads (:class:`LeapfrogOperands`); a kernel called from
        Python takes ``tuple(operands)`` (:meth:`~skinhil.model.neurons.NeuronPopulation.
        kernel_operands` says why)."""
        self.kernel_tuple = tuple(self.operands)
        """:attr:`operands` as the kernels called from Python take them."""

    def by_slot(self, forces_n: np.ndarray) -> np.ndarray:
        """External forces (n, n_masses, 3) N as :func:`leapfrog_kernel` reads them: (n, 3,
        n_slots), by component and slot, in the stepper's precision."""
        return to_slots(forces_n, self.slots, self.state.shape[2], self.dtype)

    def reset(self) -> None:
        """Back to rest: zero displacement, velocity and held input."""
        self.state[:] = 0.0

    def of_masses(self, which: int) -> np.ndarray:
        """A copy of :attr:`state` ``which`` (0 q, 1 v, 2 w, 3 the last input) per mass:
        (n_masses, 3)."""
        return self.state[which][:, self.slots].T.copy()

    def displacement_m(self) -> np.ndarray:
        """Every mass's displacement from rest now (n_masses, 3) m; fixed masses 0."""
        return self.of_masses(0)

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """Step ``len(forces_n)`` steps; ``forces_n`` is (n, n_masses, 3) N; returns
        (n, n_springs) N, row ``j`` the spring forces at the start of step ``j``."""
        forces = self.by_slot(forces_n)
        out = np.empty((forces.shape[0], self.n_springs), dtype=self.dtype)
        leapfrog_kernel(forces, out, self.dt_s, self.kernel_tuple)
        return out
