"""Decoding force direction from spikes versus noise (paper Figure 4D-G).

Protocol (documented choices):

- Trials: the 9 direction conditions of Figure 4 (:func:`skinhil.direction_conditions`,
  classes 0..8), ``reps`` noisy repetitions each from rest with the onset at t = 0
  (:func:`skinhil.simulate_trials`, neuron noise at ``snr_db``), simulated for the feature
  window only. Each SNR uses its own noise seed (``seed + index`` of the SNR in the list) and
  the same folds seed; the trials of one SNR are shared by every feature set.
- Features: :class:`skinhil.decoding.FeatureSpec` (default: PSP-filtered activity in 5 bins
  of 10 ms from the onset) of the sensors of a :class:`FeatureSet`: one sensor, a group, or
  all 338. A set's features are the columns of the all-sensor features that belong to its
  sensors (features are ordered bin-major), exactly what ``FeatureSpec(channels=...)``
  computes. Classifier :class:`DirectionDecoder` (standardisation + linear SVM).
- Evaluation: stratified 5-fold cross-validation repeated ``repeats`` times
  (:func:`skinhil.decoding.cross_validate`); chance is 1/9.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from numbers import Integral
from typing import ClassVar

import numpy as np
from tqdm.auto import tqdm

from skinhil.decoding import CVResult, DirectionDecoder, FeatureSpec, cross_validate
from skinhil.errors import ConfigError
from skinhil.model.skin import SkinModel
from skinhil.model.stimuli import direction_conditions
from skinhil.model.trials import simulate_trials
from skinhil.validation import Constraints, InstanceOf, Interval, positive, validate_params
from skinhil.workers import process_map

PAPER_SNRS_DB: tuple[float, ...] = (0.0, 5.0, 10.0, 15.0, 20.0, 30.0, math.inf)
"""The SNRs (dB) of Figure 4G."""
CHANCE = 1.0 / 9.0
"""Chance accuracy of the 9 direction conditions."""


@dataclass(frozen=True)
class DecodingSetup:
    """``reps`` trials per condition, ``folds`` x ``repeats`` cross-validation, features
    ``spec`` (all sensors; a :class:`FeatureSet` selects from them), SVM penalty ``C``,
    base ``seed``."""

    reps: int = 50
    folds: int = 5
    repeats: int = 100
    spec: FeatureSpec = field(default_factory=FeatureSpec)
    C: float = 1.0
    seed: int = 0

    _parameter_constraints: ClassVar[Constraints] = {
        "reps": Interval(Integral, 1, None, closed="left", unit="trials per condition"),
        "folds": Interval(Integral, 2, None, closed="left", unit="folds"),
        "repeats": Interval(Integral, 1, None, closed="left", unit="repeats"),
        "spec": InstanceOf(FeatureSpec, "a skinhil.decoding.FeatureSpec"),
        "C": positive("SVM penalty"),
        "seed": Interval(Integral, 0, None, closed="left"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
        if self.spec.channels is not None:
            raise ConfigError("DecodingSetup.spec must cover all sensors (channels=None); "
                              "choose sensors with a FeatureSet")


@dataclass(frozen=True)
class FeatureSet:
    """The sensors a decoder reads: ``channels`` (sorted 0-based indices), ``None`` for all."""

    name: str
    channels: tuple[int, ...] | None = None

    def spec(self, base: FeatureSpec) -> FeatureSpec:
        """``base`` restricted to this set's sensors."""
        return replace(base, channels=self.channels)

    def columns(self, base: FeatureSpec) -> np.ndarray:
        """Columns of ``base``'s all-sensor features that hold this set's features, in the
        order :meth:`FeatureSpec.transform` gives for :meth:`spec` (bin-major)."""
        chans = self.spec(base).channel_index
        return (np.arange(base.n_bins)[:, None] * base.n_channels + chans[None, :]).ravel()


def trial_features(snr_db: float, setup: DecodingSetup, model: SkinModel | None = None,
                   seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """All-sensor features (9·reps, n_features) and labels (9·reps,) of fresh noisy trials
    (noise seed ``seed``, default ``setup.seed``)."""
    spec = setup.spec
    raster = simulate_trials(direction_conditions(), setup.reps,
                             duration_s=spec.n_steps * spec.dt_s, dt_s=spec.dt_s,
                             snr_db=snr_db, seed=setup.seed if seed is None else seed,
                             model=model)
    x = spec.raster_features(raster).reshape(raster.shape[0] * raster.shape[1], -1)
    y = np.repeat(np.arange(raster.shape[0]), raster.shape[1])
    return x, y


def _decode(task: tuple[np.ndarray, np.ndarray, FeatureSpec, DecodingSetup]) -> CVResult:
    x, y, spec, setup = task
    return cross_validate(DirectionDecoder(spec, C=setup.C), x, y, folds=setup.folds,
                          repeats=setup.repeats, seed=setup.seed)


def decode_feature_sets(feature_sets: Sequence[FeatureSet],
                        snrs_db: Sequence[float] = PAPER_SNRS_DB,
                        setup: DecodingSetup | None = None, model: SkinModel | None = None,
                        workers: int | None = 1, progress: bool = False
                        ) -> dict[str, list[CVResult]]:
    """Cross-validated decoding of the 9 conditions for every feature set at every SNR:
    ``{set name: [CVResult per SNR]}``. The trials of an SNR (noise seed ``setup.seed +
    index``) are simulated once and shared by the sets; ``workers`` processes (None: every
    core) run the sets' cross-validations in parallel (the result does not depend on it)."""
    s = setup or DecodingSetup()
    names = [f.name for f in feature_sets]
    if len(set(names)) != len(names):
        raise ConfigError(f"feature set names must be distinct, got {names}")
    out: dict[str, list[CVResult]] = {n: [] for n in names}
    for i, snr in enumerate(tqdm(list(snrs_db), desc="decoding vs SNR", unit="SNR",
                                 disable=not progress)):
        x, y = trial_features(snr, s, model, seed=s.seed + i)
        results = process_map(_decode, [(x[:, f.columns(s.spec)], y, f.spec(s.spec), s)
                                        for f in feature_sets], workers)
        for name, res in zip(names, results, strict=True):
            out[name].append(res)
    return out


def split_standard_error(cv: CVResult) -> float:
    """Standard error of ``cv.accuracy`` from the random fold splits alone: the std of the
    per-repeat mean accuracies over sqrt(repeats) (NaN for one repeat)."""
    if cv.repeats < 2:
        return math.nan
    per_repeat = np.asarray(cv.fold_accuracies).reshape(cv.repeats, cv.folds).mean(axis=1)
    return float(per_repeat.std(ddof=1) / math.sqrt(cv.repeats))


def trial_standard_error(cv: CVResult) -> float:
    """Standard error of ``cv.accuracy`` from the finite number of trials (binomial,
    ``sqrt(p(1 − p)/n)`` with n the trials per repeat): what more repeats cannot reduce."""
    n = int(cv.confusion.sum()) // max(cv.repeats, 1)
    p = cv.accuracy
    return math.sqrt(p * (1.0 - p) / n) if n > 0 else math.nan
