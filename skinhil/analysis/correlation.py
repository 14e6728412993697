"""Similarity of responses across stimuli: the correlation index of Figure 3F.

For two signals ``a(t)``, ``b(t)`` the zero-lag normalised cross-correlation is
``ρ = Σ_t a b / sqrt(Σ_t a² · Σ_t b²)`` (MATLAB ``xcorr(a, b, 0, 'coeff')``: no mean
removal): 1 for identical (or proportional) signals, 0 for orthogonal ones, −1 for opposite
ones; undefined (NaN) when either is silent (:func:`zero_lag_ncc`).

The **correlation index** of two stimuli at a set of sensors (Figure 3F: the 10 springs
attached to M15) is on 0..1, "0 uncorrelated, 1 identical" as the paper describes it:

- ρ is taken over the whole response at those sensors, all sensors and all steps together
  (the spring forces in N, a (n_steps, n_sensors) block treated as one vector): it compares
  which sensors respond, how strongly and when. Averaging a per-sensor ρ instead would
  weigh a barely loaded sensor as much as the most loaded one, and in a skin that follows
  the force quasi-statically every sensor's trace has the force's time course, so per-sensor
  ρ would report little more than the signs;
- the paper's own index (:func:`similarity_matrix_per_sensor`, what 3F is judged on) is the
  per-sensor ρ (over time, one per sensor) averaged over the sensors, then ``max(·, 0)``;
  sensors silent under either input are left out of the mean. The pooled index
  (:func:`similarity_matrix`) is shown beside it;
- the index is ``max(ρ, 0)``: 1 for identical responses, 0 for uncorrelated ones. Opposite
  responses (ρ < 0) also get 0: the neurons read the force's sign (tension excites,
  compression inhibits), so opposite forces evoke unrelated spikes, not similar ones.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from skinhil.errors import ConfigError


def zero_lag_ncc(a: np.ndarray, b: np.ndarray, axis: int | tuple[int, ...] | None = 0
                 ) -> np.ndarray:
    """ρ over ``axis`` (time; ``None``: all axes) of same-shape arrays; NaN where either has
    zero energy."""
    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.shape != y.shape:
        raise ConfigError(f"signals must have the same shape, got {x.shape} and {y.shape}")
    num = np.sum(x * y, axis=axis)
    den = np.sqrt(np.sum(x * x, axis=axis) * np.sum(y * y, axis=axis))
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
    return np.asarray(out)


def correlation_index(a: np.ndarray, b: np.ndarray) -> float:
    """``max(ρ, 0)`` of two responses (n_steps, n_sensors), ρ over all their entries; NaN if
    either is silent."""
    rho = float(zero_lag_ncc(a, b, axis=None))
    return rho if np.isnan(rho) else max(rho, 0.0)


def _pairwise(responses: np.ndarray,
              index: Callable[[np.ndarray, np.ndarray], float]) -> np.ndarray:
    r = np.asarray(responses, dtype=np.float64)
    if r.ndim != 3:
        raise ConfigError(f"responses must be (n_stimuli, n_steps, n_sensors), got {r.shape}")
    n = r.shape[0]
    out = np.full((n, n), np.nan)
    for i in range(n):
        for j in range(i, n):
            out[i, j] = out[j, i] = index(r[i], r[j])
    return out


def similarity_matrix(responses: np.ndarray) -> np.ndarray:
    """Responses (n_stim, n_steps, n_sensors) → (n_stim, n_stim) pooled correlation indices
    (:func:`correlation_index`)."""
    return _pairwise(responses, correlation_index)


def per_sensor_index(a: np.ndarray, b: np.ndarray) -> float:
    """``max(mean_s ρ_s, 0)`` of two responses (n_steps, n_sensors): ρ over time per sensor,
    averaged over the sensors that respond to both; NaN if none does."""
    rho = zero_lag_ncc(a, b, axis=0)
    rho = rho[np.isfinite(rho)]
    return float("nan") if rho.size == 0 else max(float(rho.mean()), 0.0)


def similarity_matrix_per_sensor(responses: np.ndarray) -> np.ndarray:
    """Responses (n_stim, n_steps, n_sensors) → (n_stim, n_stim) per-sensor mean indices
    (:func:`per_sensor_index`: the paper's Figure 3F)."""
    return _pairwise(responses, per_sensor_index)


def sensors_of_mass(springs: np.ndarray, mass_number: int) -> np.ndarray:
    """Indices of the sensors (springs, rows of ``springs`` (n, 2) 0-based mass indices)
    attached to the paper's mass ``mass_number`` (1-based, e.g. 15 for M15), ascending."""
    s = np.asarray(springs)
    idx = np.flatnonzero(np.any(s == int(mass_number) - 1, axis=1))
    if idx.size == 0:
        raise ConfigError(f"no spring is attached to M{mass_number}")
    return idx
