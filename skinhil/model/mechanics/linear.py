"""The ``linear`` mechanics: the paper's stiffness-matrix form, stepped by exact ZOH.

Equations (paper eq. 5-8): ``M q'' + C q' + K q = f`` on the free degrees of freedom, with

- ``K = Σ_s k e_s e_sᵀ + T/L_s (I − e_s e_sᵀ)`` per spring ``s`` (axial stiffness plus the
  geometric stiffness of the baseline tension ``T``), ``C = Σ_s c e_s e_sᵀ`` (axial dampers),
  ``e_s`` the spring's rest unit vector and ``L_s`` its rest length, assembled into the 3x3
  blocks of its two masses; fixed masses are removed;
- state space ``x = [q; q']``, ``x' = A x + B u`` with ``A = [[0, I], [−M⁻¹K, −M⁻¹C]]`` and
  ``B = [[0], [M⁻¹]]``;
- exact zero-order-hold discretisation at step ``dt``:
  ``expm([[A, B], [0, 0]]·dt) = [[Ad, Bd], [0, I]]``, so ``x[k+1] = Ad x[k] + Bd u[k]`` is exact
  for an input held constant over each step, at any ``dt``.

The sensor signal of spring ``s`` between masses ``i`` and ``j`` is its length change
``k (|L0 e_s + q_j − q_i| − L0)`` (N, positive in tension) by default, or its small-displacement
limit ``k e_sᵀ (q_j − q_i)`` (``readout="axial"``): :mod:`skinhil.model.mechanics.readout`,
computed from the displacements inside the compiled step. The dynamics are the same for both.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from scipy import sparse
from scipy.linalg import expm
from threadpoolctl import threadpool_limits

from skinhil.model.geometry import Mesh
from skinhil.model.mechanics.readout import Readout, spring_signal


def spring_frames(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Rest unit vectors ``e`` (n_springs, 3), from the first mass to the second, and rest
    lengths (m)."""
    d = mesh.positions[mesh.springs[:, 1]] - mesh.positions[mesh.springs[:, 0]]
    length = np.linalg.norm(d, axis=1)
    return d / length[:, None], length


def assemble(mesh: Mesh, stiffness_n_per_m: float, damping_n_s_per_m: float,
             tension_n: float) -> tuple[sparse.csr_array, sparse.csr_array]:
    """Global K (N/m) and C (N·s/m), sparse (3·n_masses square), before removing the fixed
    masses: each spring adds its 3x3 blocks ``±(k e eᵀ + T/L (I − e eᵀ))`` and ``±c e eᵀ`` to
    the blocks of its two masses."""
    e, length = spring_frames(mesh)
    n = 3 * mesh.positions.shape[0]
    ee = e[:, :, None] * e[:, None, :]
    kb = stiffness_n_per_m * ee + (tension_n / length)[:, None, None] * (np.eye(3) - ee)
    cb = damping_n_s_per_m * ee
    i, j = mesh.springs[:, 0], mesh.springs[:, 1]
    ax = np.arange(3)
    out = []
    for blocks in (kb, cb):
        rows, cols, vals = [], [], []
        for a, b, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
            rows.append((3 * a[:, None, None] + ax[None, :, None]).repeat(3, axis=2).ravel())
            cols.append((3 * b[:, None, None] + ax[None, None, :]).repeat(3, axis=1).ravel())
            vals.append((sign * blocks).ravel())
        out.append(sparse.coo_array((np.concatenate(vals), (np.concatenate(rows),
                                                            np.concatenate(cols))),
                                    shape=(n, n)).tocsr())
    return out[0], out[1]


def free_block(matrix: sparse.csr_array, mesh: Mesh) -> sparse.csr_array:
    """The rows and columns of the free masses' degrees of freedom of a global matrix."""
    dofs = free_dofs(mesh)
    return matrix[dofs][:, dofs]


def free_dofs(mesh: Mesh) -> np.ndarray:
    """Indices into the 3·n_masses coordinate vector of the free masses' x, y, z."""
    return (3 * mesh.free[:, None] + np.arange(3)[None, :]).ravel()


def state_space(mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                damping_n_s_per_m: float, tension_n: float) -> tuple[np.ndarray, np.ndarray]:
    """Continuous-time ``A`` (150x150 at 6x6) and ``B`` (150x75) on the free degrees of
    freedom, dense (for the exact stepper of small meshes)."""
    k_glob, c_glob = assemble(mesh, stiffness_n_per_m, damping_n_s_per_m, tension_n)
    k = free_block(k_glob, mesh).toarray()
    c = free_block(c_glob, mesh).toarray()
    n = k.shape[0]
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -k / mass_kg
    a[n:, n:] = -c / mass_kg
    b = np.zeros((2 * n, n))
    b[n:, :] = np.eye(n) / mass_kg
    return a, b


def zoh(a: np.ndarray, b: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation ``(Ad, Bd)`` of ``x' = A x + B u`` at ``dt_s``;
    ``a`` (..., n, n) and ``b`` (..., n, m) may hold a stack of systems (one call)."""
    n, m = b.shape[-2:]
    big = np.zeros(a.shape[:-2] + (n + m, n + m))
    big[..., :n, :n] = a
    big[..., :n, n:] = b
    phi = expm(big * dt_s)
    return phi[..., :n, :n].copy(), phi[..., :n, n:].copy()


def sensor_matrix(mesh: Mesh, stiffness_n_per_m: float) -> sparse.csr_array:
    """Sparse ``(n_springs, n_free_dofs)`` map (338 x 75 at 6x6) from free displacements (m)
    to the axial spring forces ``k eᵀ(q_j − q_i)`` (N): the ``"axial"`` readout, linear."""
    e, _ = spring_frames(mesh)
    n_masses = mesh.positions.shape[0]
    n_springs = mesh.springs.shape[0]
    rows = np.repeat(np.arange(n_springs), 6)
    cols = (3 * mesh.springs[:, [1, 1, 1, 0, 0, 0]] + np.array([0, 1, 2, 0, 1, 2])).ravel()
    vals = (stiffness_n_per_m * np.concatenate([e, -e], axis=1)).ravel()
    full = sparse.coo_array((vals, (rows, cols)), shape=(n_springs, 3 * n_masses)).tocsr()
    return full[:, free_dofs(mesh)]


def spring_slots(mesh: Mesh, stiffness_n_per_m: float) -> tuple[np.ndarray, np.ndarray,
                                                                   np.ndarray]:
    """The sensor map in spring-vector form: ``k·e`` (3, n_springs) N/m and, per spring, the
    offsets of its first and second mass's x in the free displacement vector extended by
    three zeros, which stand for every fixed mass.

    Spring ``s`` then reads ``Σ_a ke[a, s]·(q[jj[s] + a] − q[ii[s] + a])`` (N): the same force
    as row ``s`` of :func:`sensor_matrix`, from 6 reads instead of a sparse row.
    """
    e, _ = spring_frames(mesh)
    slot = np.full(mesh.positions.shape[0], 3 * mesh.free.size, dtype=np.int64)
    slot[mesh.free] = 3 * np.arange(mesh.free.size)
    ke = np.ascontiguousarray((stiffness_n_per_m * e).T)
    return ke, slot[mesh.springs[:, 0]], slot[mesh.springs[:, 1]]


class ModalOperands(NamedTuple):
    """What the compiled modal step reads (:attr:`LinearMechanics.modal_operands`); its
    arrays are the stepper's state and scratch, updated in place."""

    phi: np.ndarray
    """Φ (n, n): the modes by column."""
    phi_t: np.ndarray
    """Φᵀ."""
    mad: np.ndarray
    """Per mode the 2x2 ``Ad`` row-major (4, n)."""
    mbd: np.ndarray
    """Per mode ``Bd`` (2, n)."""
    ke: np.ndarray
    """k·e (3, n_springs) N/m."""
    ii: np.ndarray
    """Each spring's first mass's offset in :attr:`q`."""
    jj: np.ndarray
    """Each spring's second mass's offset in :attr:`q`."""
    dofs: np.ndarray
    """The free degrees of freedom in the (n_masses·3) force vector."""
    eta: np.ndarray
    """The modal state [η; η'] (2, n)."""
    k: float
    """Spring stiffness (N/m), for the readout."""
    rest: np.ndarray
    """Rest lengths (m)."""
    length: bool
    """Whether the readout is the length change (else the axial projection)."""
    q: np.ndarray
    """Scratch: the free displacements (m) and three zeros (:func:`spring_slots`)."""
    g: np.ndarray
    """Scratch: the modal force (N)."""
    n_masses: int
    """Masses of the mesh (the force input's rows)."""


TINY = 1e-150
"""State components below this are flushed to zero: a decaying state would otherwise reach
subnormal numbers, which are ~100x slower on x86."""


@numba.njit(inline="always", fastmath=True)
def _spring_forces(ke: np.ndarray, ii: np.ndarray, jj: np.ndarray, q: np.ndarray,
                   row: np.ndarray, k: float, rest: np.ndarray,
                   length: bool) -> None:  # pragma: no cover - compiled
    # row[s] = the readout of d = x_j − x_i (N) from q, the free displacements (m) plus
    # three zeros
    for s in range(row.shape[0]):
        i = ii[s]
        j = jj[s]
        row[s] = spring_signal(ke[0, s], ke[1, s], ke[2, s], q[j] - q[i], q[j + 1] - q[i + 1],
                               q[j + 2] - q[i + 2], k, rest[s], length)


@numba.njit(inline="always", fastmath=True)
def _add_input(forces: np.ndarray, dofs: np.ndarray, table: np.ndarray,
               acc: np.ndarray) -> None:  # pragma: no cover - compiled
    # acc += Σ_j table[j] · forces[dofs[j]], skipping the (many) unloaded degrees of freedom
    for j in range(dofs.shape[0]):
        f = forces[dofs[j]]
        if f != 0.0:
            for i in range(acc.shape[0]):
                acc[i] += table[j, i] * f


@numba.njit(cache=True, fastmath=True, nogil=True)
def _advance_kernel(ad: np.ndarray, bd_t: np.ndarray, ke: np.ndarray, ii: np.ndarray,
                    jj: np.ndarray, x: np.ndarray, forces: np.ndarray, dofs: np.ndarray,
                    out: np.ndarray, k: float, rest: np.ndarray,
                    length: bool) -> None:  # pragma: no cover - compiled
    flat = forces.reshape(forces.shape[0], -1)
    n_state = x.shape[0]
    n = dofs.shape[0]
    q = np.zeros(n + 3)
    for step in range(flat.shape[0]):
        q[:n] = x[:n]
        _spring_forces(ke, ii, jj, q, out[step], k, rest, length)
        xn = ad @ x
        _add_input(flat[step], dofs, bd_t, xn)
        for i in range(n_state):
            x[i] = xn[i] if abs(xn[i]) > TINY else 0.0


@numba.njit(cache=True, fastmath=True, nogil=True)
def modal_step(fs: np.ndarray, row: np.ndarray,
               ops: ModalOperands) -> None:  # pragma: no cover - compiled
    """One step: the external forces ``fs`` (n_masses·3,) N held over it → ``row``
    (n_springs,) N, the readouts at the step's start; ``ops`` after the step."""
    eta, phi_t, mad, mbd, q, g = ops.eta, ops.phi_t, ops.mad, ops.mbd, ops.q, ops.g
    n_modes = eta.shape[1]
    # physical displacements q = Φ η (m), column by column
    q[:n_modes] = 0.0
    for m in range(n_modes):
        pos = eta[0, m]
        for i in range(n_modes):
            q[i] += phi_t[m, i] * pos
    _spring_forces(ops.ke, ops.ii, ops.jj, q, row, ops.k, ops.rest, ops.length)
    g[:] = 0.0
    _add_input(fs, ops.dofs, ops.phi, g)
    for m in range(n_modes):
        e0 = mad[0, m] * eta[0, m] + mad[1, m] * eta[1, m] + mbd[0, m] * g[m]
        e1 = mad[2, m] * eta[0, m] + mad[3, m] * eta[1, m] + mbd[1, m] * g[m]
        eta[0, m] = e0 if abs(e0) > TINY else 0.0
        eta[1, m] = e1 if abs(e1) > TINY else 0.0


@numba.njit(cache=True, nogil=True)
def modal_kernel(forces: np.ndarray, out: np.ndarray,
                 operands: tuple) -> None:  # pragma: no cover - compiled
    """forces (n, n_masses, 3) N → out (n, n_springs) N (:func:`modal_step` step by step);
    ``operands`` is ``tuple(LinearMechanics.modal_operands)``."""
    ops = ModalOperands(*operands)
    flat = forces.reshape(forces.shape[0], -1)
    for step in range(flat.shape[0]):
        modal_step(flat[step], out[step], ops)


def modal_form(k_free: np.ndarray, mass_kg: float, damping_per_stiffness_s: float,
               dt_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact per-mode ZOH when damping is proportional to stiffness (C = α K, M = m I).

    ``K = Φ diag(λ) Φᵀ`` with orthonormal Φ decouples ``m q'' + α K q' + K q = f`` into
    independent oscillators ``m η'' + α λ η' + λ η = Φᵀ f``, each discretised exactly by the
    same zero-order hold as the full system. Returns Φ (n, n), the per-mode ``Ad`` entries
    (4, n) (row-major 2x2 per mode, acting on ``[η, η']``) and ``Bd`` (2, n) acting on the
    modal force ``(Φᵀ f)_m``.
    """
    lam, phi = np.linalg.eigh(k_free)
    a = np.zeros((lam.size, 2, 2))  # one oscillator per mode, discretised in one call
    a[:, 0, 1] = 1.0
    a[:, 1, 0] = -lam / mass_kg
    a[:, 1, 1] = -damping_per_stiffness_s * lam / mass_kg
    b = np.zeros((lam.size, 2, 1))
    b[:, 1, 0] = 1.0 / mass_kg
    ad, bd = zoh(a, b, dt_s)
    mad = np.ascontiguousarray(ad.reshape(lam.size, 4).T)
    mbd = np.ascontiguousarray(bd[:, :, 0].T)
    return np.ascontiguousarray(phi), mad, mbd


class LinearMechanics:
    """Exact-ZOH stepper of the linear mechanics at a fixed ``dt_s`` (see module docstring).

    :meth:`advance` (compiled; offline and in real time) steps the modal form
    (:func:`modal_form`) when the damping is proportional to the stiffness, i.e. without
    baseline tension: the same exact discretisation, a quarter of the arithmetic (the dense
    150x150 product was the bottleneck); with tension it steps the full state space.
    """

    def __init__(self, mesh: Mesh, mass_kg: float, stiffness_n_per_m: float,
                 damping_n_s_per_m: float, tension_n: float, dt_s: float,
                 readout: Readout = "length") -> None:
        a, b = state_space(mesh, mass_kg, stiffness_n_per_m, damping_n_s_per_m, tension_n)
        self.a, self.b = a, b
        self.readout = readout
        """What each spring reports (:mod:`skinhil.model.mechanics.readout`)."""
        self.k = float(stiffness_n_per_m)
        self.rest = spring_frames(mesh)[1]
        self.length_readout = readout == "length"
        self.free = mesh.free
        self.n_masses = mesh.positions.shape[0]
        self.cy = sensor_matrix(mesh, stiffness_n_per_m)
        self.ke, self.ii, self.jj = spring_slots(mesh, stiffness_n_per_m)
        self.dofs = free_dofs(mesh)
        self.dt_s = dt_s
        self.x = np.zeros(a.shape[0])
        self.modal = tension_n == 0.0
        self.modal_operands: ModalOperands | None = None
        """What the compiled modal step takes after the forces and the output (None when
        not modal); their contents are the stepper's state, updated in place."""
        n = self.dofs.size
        # small matrices: BLAS threads only contend, on a busy machine by orders of magnitude
        with threadpool_limits(1):
            if not self.modal:  # the full state space, discretised once (modal form: below)
                self.ad, self.bd = zoh(a, b, dt_s)
            else:
                self.phi, self.mad, self.mbd = modal_form(
                    -a[n:, :n] * mass_kg, mass_kg, damping_n_s_per_m / stiffness_n_per_m, dt_s)
        if not self.modal:
            self.bd_t = np.ascontiguousarray(self.bd.T)
        else:
            self.phi_t = np.ascontiguousarray(self.phi.T)
            self.eta = np.zeros((2, n))
            self.modal_operands = ModalOperands(
                phi=self.phi, phi_t=self.phi_t, mad=self.mad, mbd=self.mbd, ke=self.ke,
                ii=self.ii, jj=self.jj, dofs=self.dofs, eta=self.eta, k=self.k, rest=self.rest,
                length=self.length_readout, q=np.zeros(n + 3), g=np.zeros(n),
                n_masses=self.n_masses)
        self.kernel_tuple = None if self.modal_operands is None else tuple(self.modal_operands)
        """:attr:`modal_operands` as the kernels called from Python take them (None when not
        modal; :meth:`~skinhil.model.neurons.NeuronPopulation.kernel_operands` says why)."""

    def reset(self) -> None:
        """Back to rest: zero displacement and velocity."""
        self.x[:] = 0.0
        if self.modal:
            self.eta[:] = 0.0

    def state(self) -> np.ndarray:
        """The physical state ``[q; q']`` (m, m/s) of the free degrees of freedom, (150,)."""
        if self.modal:
            return np.concatenate([self.phi @ self.eta[0], self.phi @ self.eta[1]])
        return self.x.copy()

    def displacement_m(self) -> np.ndarray:
        """Every mass's displacement from rest now (n_masses, 3) m; fixed masses 0."""
        q = np.zeros((self.n_masses, 3))
        q[self.free] = self.state()[: self.dofs.size].reshape(-1, 3)
        return q

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """Step ``len(forces_n)`` steps; ``forces_n`` is (n, 77, 3) N; returns (n, 338) N.

        Row ``j`` of the result is the spring forces at the start of step ``j``; input ``j`` is
        then held over the step.
        """
        out = np.empty((forces_n.shape[0], self.cy.shape[0]))
        forces = np.ascontiguousarray(forces_n, dtype=np.float64)
        if self.kernel_tuple is not None:
            modal_kernel(forces, out, self.kernel_tuple)
        else:
            _advance_kernel(self.ad, self.bd_t, self.ke, self.ii, self.jj, self.x, forces,
                            self.dofs, out, self.k, self.rest, self.length_readout)
        return out
