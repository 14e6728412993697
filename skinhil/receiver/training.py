"""Fit the direction decoder the receiver uses, on simulated Figure 4 trials.

Protocol: the 9 direction conditions (:func:`skinhil.direction_conditions`, classes 0..8),
``reps`` noisy trials each at ``snr_db``, from rest with the onset at t = 0
(:func:`skinhil.simulate_trials`); only the decision window is simulated. Features and
classifier are :mod:`skinhil.decoding`'s (time-binned PSP activity of all 338 sensors, linear
SVM); its repeated cross-validation gives the offline accuracy and confusion matrix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from skinhil.decoding import DirectionDecoder, FeatureSpec, cross_validate
from skinhil.psp import PSPFilterBank
from skinhil.stimuli import direction_conditions
from skinhil.trials import simulate_trials

WINDOW_S = 0.05
"""Decision window (s) after the onset: the evoked spikes come within ~20 ms."""
BIN_S = 0.01
"""Feature time bin (s)."""
CV_FOLDS = 5
CV_REPEATS = 3


@dataclass(frozen=True)
class TrainingReport:
    """Offline cross-validated accuracy (0..1), its spread and the confusion matrix."""

    snr_db: float
    reps: int
    seed: int
    cv_accuracy: float
    cv_accuracy_std: float
    confusion: np.ndarray
    classes: tuple[int, ...]


def feature_spec(dt_s: float = 1e-4) -> Any:
    """The receiver's feature definition: all sensors, ``WINDOW_S`` in ``BIN_S`` bins."""
    return FeatureSpec(dt_s=dt_s, window_s=WINDOW_S, bin_s=BIN_S)


def training_trials(snr_db: float, reps: int, seed: int, dt_s: float = 1e-4,
                    progress: bool = False) -> tuple[np.ndarray, np.ndarray, Any]:
    """Features (n_trials, n_features), labels (n_trials,) and the feature spec."""
    spec = feature_spec(dt_s)
    raster = simulate_trials(direction_conditions(), reps, duration_s=spec.n_steps * dt_s,
                             dt_s=dt_s, snr_db=snr_db, seed=seed, progress=progress)
    psp = PSPFilterBank(raster.shape[-1], dt_s, spec.psp).filter(raster)
    x = spec.transform(psp).reshape(raster.shape[0] * raster.shape[1], -1)
    y = np.repeat(np.arange(raster.shape[0]), raster.shape[1])
    return x, y, spec


def train_decoder(snr_db: float = 10.0, reps: int = 50, seed: int = 0, dt_s: float = 1e-4,
                  progress: bool = False, cross_validation: bool = True
                  ) -> tuple[Any, TrainingReport]:
    """Simulate, cross-validate and fit; return the fitted decoder and the report."""
    x, y, spec = training_trials(snr_db, reps, seed, dt_s, progress)
    acc, std, conf = math.nan, math.nan, np.zeros((9, 9), dtype=np.int64)
    if cross_validation:
        cv = cross_validate(DirectionDecoder(spec), x, y, folds=CV_FOLDS,
                            repeats=CV_REPEATS, seed=seed)
        acc, std, conf = cv.accuracy, cv.accuracy_std, cv.confusion
    decoder = DirectionDecoder(spec).fit(x, y)
    return decoder, TrainingReport(snr_db, reps, seed, float(acc), float(std),
                                   np.asarray(conf), tuple(int(c) for c in decoder.classes_))
