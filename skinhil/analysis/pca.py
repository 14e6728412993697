"""Information content by principal components: variance-explained curves and their ratios.

Conventions (the paper gives the measures, these are the documented choices):

- **Data matrix** of one phase: one **sample** per time step of the phase window, for every
  stimulus condition, stacked (n_stimuli x n_phase_steps rows); one **feature** per sensor
  (the spring force in N, all 338 by default). Each feature is centred over the samples; no
  scaling (all features share the unit, so large responses weigh more, as in a covariance
  PCA).
- **Variance-explained curve** ``c(k)``: cumulative fraction of the total variance held by
  the first k principal components, k = 1..n_features (``c(n_features) = 1``).
- **nPC99**: the least k with ``c(k) ≥ 0.99``; the **nPC ratio** is nPC99(indentation) /
  nPC99(post-indentation): above 1 when the indentation phase spreads its variance over more
  dimensions.
- **Area between the curves**: ``Σ_k [c_ind(k) − c_post(k)]`` over k = 1..n_features (in units
  of PCs, a unit-spaced Riemann sum), the paper's sign: **negative** when the indentation
  curve rises more slowly, i.e. the indentation phase holds more independent components
  (more information).
- **Signal-information ratio (SIR)** of a phase: the raw (uncentred) data projected on each of
  the first 3 principal axes gives a score trace ``z_k``; ``SIR_k = mean|z_k| / std(z_k)``
  (sustained component over its fluctuation) and the phase's SIR is the mean over k = 1, 2,
  3; the **SIR ratio** is SIR(indentation) / SIR(post-indentation). This is the project's
  reading of the paper's "mean/std of the first 3 PCs" (eq. 10).
- **Literal eq. 10 SIR**: the same words read literally, mean over std of each score trace,
  ``|mean(z_k)| / std(z_k)`` (the signed mean; its absolute value only because a principal
  axis' sign is arbitrary), averaged over k = 1, 2, 3. It differs from the reading above
  where a score oscillates about zero (a ringing post-indentation phase): its mean|z| is
  large, its signed mean small. Reported beside it, in every table and sweep.

A phase with no variance at all (e.g. a silent post-indentation) has undefined curves: its
nPC99 and SIR are NaN, as are the ratios and the area that need it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinhil.errors import ConfigError

N_SIR_COMPONENTS = 3
"""Principal components entering the signal-information ratio."""
VARIANCE_TARGET = 0.99
"""Fraction of variance for nPC99."""


@dataclass(frozen=True)
class PhasePCA:
    """PCA of one phase: ``curve`` (n_features,) cumulative variance fractions (NaN if the
    phase has no variance), ``eigenvalues`` (n_features,) in N², ``axes`` (n_features,
    n_features) principal axes as columns, ``scores`` (n_samples, 3) uncentred projections on
    the first three axes."""

    curve: np.ndarray
    eigenvalues: np.ndarray
    axes: np.ndarray
    scores: np.ndarray

    @property
    def npc99(self) -> float:
        """Least number of PCs reaching 99% of the variance (NaN without variance)."""
        return n_components_for(self.curve, VARIANCE_TARGET)

    @property
    def sir(self) -> float:
        """Signal-information ratio of the first three PCs (see module docstring)."""
        return signal_information_ratio(self.scores)

    @property
    def sir_literal(self) -> float:
        """The literal eq. 10 signal-information ratio (see module docstring)."""
        return signal_information_ratio_literal(self.scores)


def phase_pca(samples: np.ndarray) -> PhasePCA:
    """PCA of a data matrix (n_samples, n_features): samples are rows, features columns."""
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 2 or x.shape[0] < 2 or x.shape[1] < 1:
        raise ConfigError(f"PCA needs a (n_samples >= 2, n_features >= 1) matrix, got {x.shape}")
    xc = x - x.mean(axis=0)
    gram = xc.T @ xc / (x.shape[0] - 1)
    lam, vec = np.linalg.eigh(gram)
    order = np.argsort(lam)[::-1]
    lam = np.clip(lam[order], 0.0, None)
    vec = vec[:, order]
    total = lam.sum()
    if not total > 0.0:
        curve = np.full(lam.size, np.nan)
    else:
        curve = np.minimum(np.cumsum(lam) / total, 1.0)
    k = min(N_SIR_COMPONENTS, vec.shape[1])
    return PhasePCA(curve, lam, vec, x @ vec[:, :k])


def variance_explained(samples: np.ndarray) -> np.ndarray:
    """Cumulative variance-explained curve (n_features,) of a data matrix; see phase_pca."""
    return phase_pca(samples).curve


def n_components_for(curve: np.ndarray, fraction: float = VARIANCE_TARGET) -> float:
    """Least k (1-based) with ``curve[k-1] >= fraction``; NaN for an undefined curve."""
    c = np.asarray(curve, dtype=float)
    if c.size == 0 or np.isnan(c).any():
        return math.nan
    return float(np.argmax(c >= fraction - 1e-12) + 1)


def area_between(curve_ind: np.ndarray, curve_post: np.ndarray) -> float:
    """``Σ_k [curve_ind(k) − curve_post(k)]`` (the paper's sign: negative when the
    indentation phase needs more components); the shorter curve is padded with 1 (a curve
    of fewer features has reached all of its variance)."""
    a = np.asarray(curve_ind, dtype=float)
    b = np.asarray(curve_post, dtype=float)
    n = max(a.size, b.size)
    a = np.concatenate([a, np.ones(n - a.size)])
    b = np.concatenate([b, np.ones(n - b.size)])
    return float(np.sum(a - b))


def signal_information_ratio(scores: np.ndarray) -> float:
    """Mean over the columns of ``mean|z| / std(z)`` (NaN if any column is constant)."""
    z, std = _scores_and_std(scores)
    return math.nan if std is None else float(np.mean(np.abs(z).mean(axis=0) / std))


def _scores_and_std(scores: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The scores as floats and each column's std (None if any column is constant)."""
    z = np.asarray(scores, dtype=float)
    if z.ndim != 2 or z.shape[0] < 2:
        raise ConfigError(f"scores must be (n_samples >= 2, n_components), got {z.shape}")
    std = z.std(axis=0)
    if np.any(std <= 1e-12 * max(np.abs(z).max(), np.finfo(float).tiny)):
        return z, None
    return z, std


def signal_information_ratio_literal(scores: np.ndarray) -> float:
    """Mean over the columns of ``|mean(z)| / std(z)``: eq. 10 read literally (NaN if any
    column is constant)."""
    z, std = _scores_and_std(scores)
    return math.nan if std is None else float(np.mean(np.abs(z.mean(axis=0)) / std))
