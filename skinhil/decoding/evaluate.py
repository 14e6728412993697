"""Repeated stratified k-fold cross-validation of a decoder (paper: 5 folds, 100 repeats).

For each repeat, the trials are split into ``folds`` stratified folds (scikit-learn
``RepeatedStratifiedKFold`` seeded by ``seed``); a fresh clone of the estimator is fitted on
the other folds and tested on each. Reported:

- ``accuracy``: mean test accuracy over all ``folds x repeats`` test folds;
- ``accuracy_std``: standard deviation of those fold accuracies;
- ``confusion``: counts (true class rows, predicted class columns, order ``classes``) summed
  over all test folds of all repeats, so each row sums to ``repeats x`` that class's trials;
  :attr:`CVResult.confusion_fraction` gives it row-normalised.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import clone
from sklearn.metrics import confusion_matrix
from sklearn.model_selection import RepeatedStratifiedKFold
from tqdm.auto import tqdm

from skinhil.errors import ConfigError


@dataclass(frozen=True)
class CVResult:
    """Outcome of :func:`cross_validate` (accuracies are fractions in 0..1)."""

    accuracy: float
    accuracy_std: float
    fold_accuracies: np.ndarray
    confusion: np.ndarray
    classes: np.ndarray
    folds: int
    repeats: int

    @property
    def confusion_fraction(self) -> np.ndarray:
        """Confusion matrix with each true-class row divided by its total (rows sum to 1)."""
        totals = self.confusion.sum(axis=1, keepdims=True)
        return np.asarray(self.confusion / np.maximum(totals, 1))


def _one_fold(estimator: Any, x: np.ndarray, y: np.ndarray, train: np.ndarray,
              test: np.ndarray, classes: np.ndarray) -> tuple[float, np.ndarray]:
    model = clone(estimator).fit(x[train], y[train])
    pred = model.predict(x[test])
    return float(np.mean(pred == y[test])), confusion_matrix(y[test], pred, labels=classes)


def cross_validate(estimator: Any, x: Any, y: Any, folds: int = 5, repeats: int = 100,
                   seed: int | None = 0, progress: bool = False) -> CVResult:
    """Repeated stratified ``folds``-fold cross-validation of ``estimator`` on ``(x, y)``.

    Raises ConfigError when a class has fewer trials than ``folds``.
    """
    arr = np.asarray(x, dtype=np.float64)
    labels = np.asarray(y)
    if arr.ndim != 2 or labels.shape != (arr.shape[0],):
        raise ConfigError(f"cross-validation needs x (n, features) and y (n,), got "
                          f"{arr.shape} and {labels.shape}")
    if folds < 2 or repeats < 1:
        raise ConfigError(f"need folds >= 2 and repeats >= 1, got {folds} and {repeats}")
    classes, counts = np.unique(labels, return_counts=True)
    if counts.min() < folds:
        raise ConfigError(f"class {classes[np.argmin(counts)]!r} has {counts.min()} trials, "
                          f"fewer than the {folds} folds; simulate more repetitions")
    splitter = RepeatedStratifiedKFold(n_splits=folds, n_repeats=repeats, random_state=seed)
    splits = list(splitter.split(arr, labels))
    results = [_one_fold(estimator, arr, labels, tr, te, classes)
               for tr, te in tqdm(splits, desc="cross-validation", unit="fold",
                                  disable=not progress)]
    accs = np.array([r[0] for r in results])
    conf = np.sum([r[1] for r in results], axis=0).astype(np.int64)
    return CVResult(float(accs.mean()), float(accs.std()), accs, conf, classes, folds, repeats)
