"""Similarity of responses across stimuli: zero-lag normalised cross-correlation (Figure 3F).

For two signals ``a(t)``, ``b(t)`` of one sensor (spring force, N, over the simulated steps)
the zero-lag normalised cross-correlation is ``ρ = Σ_t a b / sqrt(Σ_t a² · Σ_t b²)``
(MATLAB ``xcorr(a, b, 0, 'coeff')``: no mean removal): 1 for identical (or proportional)
signals, 0 for orthogonal ones, −1 for opposite ones; undefined (NaN) when either is silent.
The **similarity** of two stimuli over a set of sensors is the mean of ρ over the sensors
where it is defined; Figure 3F uses the sensors of M15, the springs attached to M15.
"""

from __future__ import annotations

import numpy as np

from skinhil.errors import ConfigError


def zero_lag_ncc(a: np.ndarray, b: np.ndarray, axis: int = 0) -> np.ndarray:
    """ρ along ``axis`` (time) of same-shape arrays; NaN where either has zero energy."""
    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.shape != y.shape:
        raise ConfigError(f"signals must have the same shape, got {x.shape} and {y.shape}")
    num = np.sum(x * y, axis=axis)
    den = np.sqrt(np.sum(x * x, axis=axis) * np.sum(y * y, axis=axis))
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
    return np.asarray(out)


def similarity_matrix(responses: np.ndarray) -> np.ndarray:
    """Responses (n_stim, n_steps, n_sensors) → (n_stim, n_stim) mean ρ over the sensors.

    Entry (i, j) averages ρ of stimulus i's and j's signal on each sensor, over the sensors
    where both are non-silent (NaN if none).
    """
    r = np.asarray(responses, dtype=np.float64)
    if r.ndim != 3:
        raise ConfigError(f"responses must be (n_stimuli, n_steps, n_sensors), got {r.shape}")
    n = r.shape[0]
    out = np.full((n, n), np.nan)
    for i in range(n):
        for j in range(i, n):
            rho = zero_lag_ncc(r[i], r[j], axis=0)
            if np.any(~np.isnan(rho)):
                out[i, j] = out[j, i] = float(np.nanmean(rho))
    return out


def sensors_of_mass(springs: np.ndarray, mass_number: int) -> np.ndarray:
    """Indices of the sensors (springs, rows of ``springs`` (n, 2) 0-based mass indices)
    attached to the paper's mass ``mass_number`` (1-based, e.g. 15 for M15)."""
    s = np.asarray(springs)
    idx = np.flatnonzero(np.any(s == int(mass_number) - 1, axis=1))
    if idx.size == 0:
        raise ConfigError(f"no spring is attached to M{mass_number}")
    return idx
