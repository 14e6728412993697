"""Exact linear responses of many stimuli in a reduced sensor basis, for parameter sweeps.

Why: a K x C sweep simulates the paper stimuli at hundreds of parameter points; the full
338-sensor simulation costs ~50 ms per point, this costs a few.

How (``linear`` mechanics without baseline tension, ``M = m I``, and the ``axial`` readout,
linear in the displacements: the default length readout is not, so it has no such shortcut
and :func:`supports` sends it to the exact stepper): the damping is then
proportional to the stiffness, ``C = (c/k) K``, so the modes of ``K``
(:func:`skinhil.model.mechanics.linear.modal_form`, ``K = Φ diag(λ) Φᵀ``) decouple the equations
into 75 oscillators, each discretised by the same exact zero-order hold as
:class:`skinhil.SkinModel`. Every stimulus here has peak forces ``F_s`` and a time profile
``p(t)`` (Figure 1D), so mode m's response is ``(Φᵀ F_s)_m · h_m(t)`` with ``h_m`` the mode's
response to ``p`` alone (one IIR filter per mode). The 338 sensor forces are
``Y_s(t) = Cy Φ diag(Φᵀ F_s) h(t)``; with the thin QR factorisation ``Cy Φ = Q R`` (Q has
orthonormal columns) the **reduced responses** ``R diag(Φᵀ F_s) h(t)`` (75 per step) give the
same PCA eigenvalues and the same projections as the 338 forces, since ``Y = Q·(reduced)``;
:func:`full_forces` maps them back. Rows are at ``t = k·dt`` as in :meth:`SkinModel.simulate`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from skinhil.errors import ConfigError
from skinhil.model.geometry import Mesh, build_mesh, format_size
from skinhil.model.mechanics.linear import (
    assemble,
    free_block,
    free_dofs,
    modal_form,
    sensor_matrix,
)
from skinhil.model.skin import SkinParams
from skinhil.model.stimuli import Stimulus


@dataclass(frozen=True)
class ReducedResponses:
    """``reduced`` (n_stim, n_steps, 75) responses and ``basis`` Q (338, 75): forces = r @ Qᵀ."""

    reduced: np.ndarray
    basis: np.ndarray

    def full_forces(self) -> np.ndarray:
        """The 338 spring forces (N): (n_stim, n_steps, 338)."""
        return np.asarray(self.reduced @ self.basis.T)


@functools.lru_cache(maxsize=8)
def _unit_structure(spacing_m: float, layer_gap_m: float,
                    size: tuple[int, int]) -> tuple[Mesh, np.ndarray, np.ndarray]:
    mesh = build_mesh(spacing_m, layer_gap_m, size)
    k_glob, _ = assemble(mesh, 1.0, 0.0, 0.0)
    dofs = free_dofs(mesh)
    return mesh, free_block(k_glob, mesh).toarray(), dofs


def supports(params: SkinParams) -> bool:
    """Whether :func:`reduced_responses` applies: linear mechanics, no baseline tension and
    the axial readout. The length readout is not linear in the displacements, so the sensor
    forces do not lie in the span of ``Cy Φ``: no reduced basis gives them exactly, and those
    points go through the exact stepper (:meth:`skinhil.SkinModel.simulate_many`)."""
    return (params.dynamics == "linear" and params.tension_n == 0.0
            and params.readout == "axial")


def reduced_responses(params: SkinParams, stimuli: Sequence[Stimulus], duration_s: float,
                      dt_s: float) -> ReducedResponses:
    """Exact responses of ``stimuli`` from rest, ``round(duration_s/dt_s)`` steps of ``dt_s``."""
    if not supports(params):
        raise ConfigError("the modal sweep path needs mechanics='linear', tension_n=0 and "
                          "readout='axial'; use SkinModel.simulate_many for other models")
    mesh, k_unit, dofs = _unit_structure(params.spacing_m, params.layer_gap_m, params.size)
    k = params.stiffness_n_per_m
    phi, mad, mbd = modal_form(k * k_unit, params.mass_kg, params.damping_n_s_per_m / k, dt_s)
    q, r = np.linalg.qr(sensor_matrix(mesh, k) @ phi)
    n_steps = max(1, int(round(duration_s / dt_s)))
    t = np.arange(n_steps) * dt_s
    # per mode: x[k+1] = Ad x[k] + Bd u[k], output x0[k]  →  IIR filter on the profile
    b = np.stack([np.zeros(phi.shape[1]), mbd[0], mad[1] * mbd[1] - mad[3] * mbd[0]], axis=1)
    a = np.stack([np.ones(phi.shape[1]), -(mad[0] + mad[3]), mad[0] * mad[3] - mad[1] * mad[2]],
                 axis=1)
    out = np.empty((len(stimuli), n_steps, phi.shape[1]))
    cache: dict[tuple[float, float, float], np.ndarray] = {}
    for i, s in enumerate(stimuli):
        if s.size != params.size:
            raise ConfigError(f"stimulus {s.name!r} is defined on a {format_size(s.size)} "
                              f"skin, the model is {format_size(params.size)}")
        if np.any(s.peak_forces_n[mesh.fixed] != 0.0):
            raise ConfigError(f"stimulus {s.name!r} pushes fixed masses, which cannot move")
        key = (s.onset_s, s.indentation_s, s.decay_tau_s)
        if key not in cache:
            p = s.profile(t)
            cache[key] = np.stack([lfilter(b[m], a[m], p) for m in range(phi.shape[1])], axis=1)
        weights = phi.T @ s.peak_forces_n.reshape(-1)[dofs]
        out[i] = (cache[key] * weights) @ r.T
    return ReducedResponses(out, q)
