"""Decoding force direction from spikes versus noise (paper Figure 4D-G).

Protocol (documented choices):

- Trials: the 9 direction conditions of Figure 4 (:func:`skinhil.direction_conditions`,
  classes 0..8), ``reps`` noisy repetitions each from rest with the onset at t = 0
  (:func:`skinhil.simulate_trials`, neuron noise at ``snr_db``), simulated for the feature
  window only.
- Features: :class:`skinhil.decoding.FeatureSpec` (default: PSP-filtered activity of all 338
  sensors in 5 bins of 10 ms from the onset); classifier :class:`DirectionDecoder`.
- Evaluation: stratified 5-fold cross-validation repeated ``repeats`` times
  (:func:`skinhil.decoding.cross_validate`); chance is 1/9.
- Each SNR uses its own noise seed (``seed + index``), the same folds seed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from skinhil.decoding import CVResult, DirectionDecoder, FeatureSpec, cross_validate
from skinhil.skin import SkinModel
from skinhil.stimuli import Stimulus, direction_conditions
from skinhil.trials import simulate_trials

PAPER_SNRS_DB: tuple[float, ...] = (0.0, 5.0, 10.0, 15.0, 20.0, 30.0, math.inf)
"""The SNRs (dB) of Figure 4G."""


@dataclass(frozen=True)
class DecodingSetup:
    """``reps`` trials per condition, ``folds`` x ``repeats`` cross-validation, features
    ``spec``, SVM penalty ``C``, base ``seed``."""

    reps: int = 50
    folds: int = 5
    repeats: int = 100
    spec: FeatureSpec = field(default_factory=FeatureSpec)
    C: float = 1.0
    seed: int = 0


def trial_features(snr_db: float, setup: DecodingSetup, model: SkinModel | None = None,
                   seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Features (9·reps, n_features) and labels (9·reps,) of fresh noisy trials."""
    spec = setup.spec
    raster = simulate_trials(direction_conditions(), setup.reps,
                             duration_s=spec.n_steps * spec.dt_s, dt_s=spec.dt_s,
                             snr_db=snr_db, seed=setup.seed if seed is None else seed,
                             model=model)
    x = spec.raster_features(raster).reshape(raster.shape[0] * raster.shape[1], -1)
    y = np.repeat(np.arange(raster.shape[0]), raster.shape[1])
    return x, y


def decode_at_snr(snr_db: float, setup: DecodingSetup, model: SkinModel | None = None,
                  seed: int | None = None, n_jobs: int = 1) -> CVResult:
    """Cross-validated decoding of the 9 conditions at ``snr_db``."""
    x, y = trial_features(snr_db, setup, model, seed)
    return cross_validate(DirectionDecoder(setup.spec, C=setup.C), x, y, folds=setup.folds,
                          repeats=setup.repeats, seed=setup.seed, n_jobs=n_jobs)


def accuracy_vs_snr(snrs_db: Sequence[float] = PAPER_SNRS_DB,
                    setup: DecodingSetup | None = None, model: SkinModel | None = None,
                    n_jobs: int = 1, progress: bool = False) -> list[CVResult]:
    """:func:`decode_at_snr` at each SNR (noise seed ``setup.seed + index``)."""
    s = setup or DecodingSetup()
    return [decode_at_snr(snr, s, model, seed=s.seed + i, n_jobs=n_jobs)
            for i, snr in enumerate(tqdm(list(snrs_db), desc="decoding vs SNR", unit="SNR",
                                         disable=not progress))]


def repetition_raster(stimulus: Stimulus, sensor: int, reps: int = 50,
                      snr_db: float = 20.0, duration_s: float = 0.5, dt_s: float = 1e-4,
                      seed: int = 0, model: SkinModel | None = None) -> np.ndarray:
    """Spikes of one ``sensor`` over ``reps`` repetitions of ``stimulus``: (reps, n_steps)."""
    raster = simulate_trials([stimulus], reps, duration_s=duration_s, dt_s=dt_s,
                             snr_db=snr_db, seed=seed, model=model)
    return np.asarray(raster[0, :, :, sensor])
