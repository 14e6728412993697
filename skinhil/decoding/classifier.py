"""The force-direction decoder: standardisation + linear SVM, scikit-learn conventions.

``DirectionDecoder(spec).fit(X, y)`` learns, on feature vectors ``X`` (n_trials,
spec.n_features) from :meth:`FeatureSpec.transform` and labels ``y``:

- a standardisation ``z = (x − mean_) / scale_`` (scikit-learn ``StandardScaler``; a constant
  feature gets scale 1);
- a linear SVM (scikit-learn ``SVC(kernel="linear")``, libsvm: hinge loss, penalty ``C``,
  one-vs-one for more than two classes) giving one hyperplane per class pair,
  ``coef_`` (n_pairs, n_features) and ``intercept_`` (n_pairs,), pairs ordered
  (0,1), (0,2), ..., (1,2), ... over ``classes_``; ``n_pairs = n(n−1)/2`` (1 for two classes).

Decisions are computed from these plain arrays only, so a decoder saved with
:meth:`DirectionDecoder.save` and loaded again predicts exactly the same:
``d_k = z @ coef_[k] + intercept_[k]`` for pair k = (i, j) votes for i when ``d_k ≥ 0``, else
for j; ``decision_function`` is scikit-learn's one-vs-rest shaped aggregate ``votes +
c / (3 (|c| + 1))`` with ``c`` the summed pair values for (+) and against (−) each class, and
``predict`` takes its largest entry (ties of votes go to the larger summed value), as
scikit-learn's ``SVC(break_ties=True)`` does. For two
classes ``decision_function`` is ``d_0`` and positive means ``classes_[1]``.

``SVC`` was chosen over ``LinearSVC``: on these features (a few hundred trials, ~1700
features) it fits 5-80 times faster and, one-vs-one, decodes the noisy conditions better.
It is fitted on the precomputed linear kernel ``Z Zᵀ`` (one BLAS product instead of libsvm's
per-pair dot products: 4x faster, the same optimisation problem); the hyperplanes are then
read off the fitted SVM's response to unit kernel rows.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from skinhil.decoding.features import FeatureSpec
from skinhil.decoding.model_file import load_decoder, save_decoder
from skinhil.errors import ConfigError, ModelFileError

logger = logging.getLogger(__name__)


class DirectionDecoder(ClassifierMixin, BaseEstimator):  # type: ignore[misc]
    """Linear SVM on standardised PSP features (see module docstring).

    Parameters: ``spec`` the feature definition (default :class:`FeatureSpec`), ``C`` the SVM
    penalty, ``max_iter`` (−1: no limit) and ``tol`` the libsvm solver's limits.
    Learned: ``spec_``, ``classes_``, ``coef_``, ``intercept_``, ``mean_``, ``scale_``,
    ``n_features_in_``.
    """

    def __init__(self, spec: FeatureSpec | None = None, C: float = 1.0,
                 max_iter: int = -1, tol: float = 1e-3) -> None:
        self.spec = spec
        self.C = C
        self.max_iter = max_iter
        self.tol = tol

    def _check_x(self, x: Any, n_features: int) -> np.ndarray:
        arr = np.asarray(x, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != n_features:
            raise ConfigError(f"features have shape {arr.shape}; expected (n_trials, "
                              f"{n_features}) as the feature spec defines")
        if not np.all(np.isfinite(arr)):
            raise ConfigError("features contain NaN or inf; check the PSP traces")
        return arr

    def fit(self, x: Any, y: Any) -> DirectionDecoder:
        """Learn the scaler and the linear SVM from ``x`` (n, n_features) and labels ``y``."""
        spec = self.spec if self.spec is not None else FeatureSpec()
        if not isinstance(spec, FeatureSpec):
            raise ConfigError("DirectionDecoder.spec must be a skinhil.decoding.FeatureSpec")
        arr = self._check_x(x, spec.n_features)
        labels = np.asarray(y)
        if labels.shape != (arr.shape[0],):
            raise ConfigError(f"labels have shape {labels.shape}; expected ({arr.shape[0]},)")
        classes = np.unique(labels)
        if classes.size < 2:
            raise ConfigError("need trials of at least two classes to fit a decoder")
        scaler = StandardScaler().fit(arr)
        z = scaler.transform(arr)
        svm = SVC(kernel="precomputed", C=self.C, max_iter=self.max_iter, tol=self.tol,
                  decision_function_shape="ovo").fit(z @ z.T, labels)
        # the SVM is linear in the kernel row k(x) = z_train @ z_x: reading its response to
        # unit rows gives each pair's weights on the support vectors, hence the hyperplanes
        sv = svm.support_
        unit = np.zeros((sv.size, z.shape[0]))
        unit[np.arange(sv.size), sv] = 1.0
        base = svm.decision_function(np.zeros((1, z.shape[0]))).reshape(1, -1)
        weights = svm.decision_function(unit).reshape(sv.size, -1) - base
        logger.debug("linear SVM: %d support vectors", int(sv.size))
        self.spec_ = spec
        self.classes_ = svm.classes_
        self.coef_ = np.ascontiguousarray(weights.T @ z[sv], dtype=np.float64)
        self.intercept_ = np.asarray(base[0], dtype=np.float64)
        self.mean_ = np.asarray(scaler.mean_, dtype=np.float64)
        self.scale_ = np.asarray(scaler.scale_, dtype=np.float64)
        self.n_features_in_ = arr.shape[1]
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "coef_"):
            raise ConfigError("this DirectionDecoder is not fitted yet; call fit() or load()")

    def pair_decisions(self, x: Any) -> np.ndarray:
        """The one-vs-one hyperplane values ``d`` (n, n_pairs) (see module docstring)."""
        self._check_fitted()
        z = (self._check_x(x, self.n_features_in_) - self.mean_) / self.scale_
        return np.asarray(z @ self.coef_.T + self.intercept_)

    def decision_function(self, x: Any) -> np.ndarray:
        """Per-class decision values (n, n_classes); (n,) for two classes (> 0 → classes_[1])."""
        d = self.pair_decisions(x)
        n_classes = len(self.classes_)
        if n_classes == 2:
            return np.asarray(d[:, 0])
        votes = np.zeros((d.shape[0], n_classes))
        conf = np.zeros((d.shape[0], n_classes))
        k = 0
        for i in range(n_classes):
            for j in range(i + 1, n_classes):
                wins = d[:, k] >= 0
                votes[wins, i] += 1
                votes[~wins, j] += 1
                conf[:, i] += d[:, k]
                conf[:, j] -= d[:, k]
                k += 1
        return np.asarray(votes + conf / (3.0 * (np.abs(conf) + 1.0)))

    def predict(self, x: Any) -> np.ndarray:
        """Predicted class of each row of ``x``."""
        scores = self.decision_function(x)
        if scores.ndim == 1:
            return np.asarray(self.classes_[(scores > 0).astype(np.int64)])
        return np.asarray(self.classes_[np.argmax(scores, axis=1)])

    def save(self, path: str | Path) -> None:
        """Write the fitted decoder as plain data (see :mod:`skinhil.decoding.model_file`)."""
        self._check_fitted()
        save_decoder(self, path)

    @classmethod
    def load(cls, path: str | Path, n_channels: int | None = None,
             dt_s: float | None = None) -> DirectionDecoder:
        """Read a decoder written by :meth:`save`; refuse pickles, corrupted, mismatched
        (``n_channels``/``dt_s`` of the stream, when given) or other-version files with
        :class:`ModelFileError`."""
        content = load_decoder(path)
        decoder = cls(spec=content.spec, C=content.C, max_iter=content.max_iter, tol=content.tol)
        decoder.spec_ = content.spec
        decoder.classes_ = content.arrays["classes"]
        decoder.coef_ = content.arrays["coef"]
        decoder.intercept_ = content.arrays["intercept"]
        decoder.mean_ = content.arrays["mean"]
        decoder.scale_ = content.arrays["scale"]
        decoder.n_features_in_ = content.n_features
        if n_channels is not None or dt_s is not None:
            decoder.check_stream(content.spec.n_channels if n_channels is None else n_channels,
                                 content.spec.dt_s if dt_s is None else dt_s)
        return decoder

    def check_stream(self, n_channels: int, dt_s: float) -> None:
        """Raise ModelFileError unless the decoder was made for this channel count and step."""
        self._check_fitted()
        spec = self.spec_
        if int(n_channels) != spec.n_channels:
            raise ModelFileError(f"the decoder expects {spec.n_channels} channels but the "
                                 f"stream has {n_channels}; train a decoder for this stream")
        if abs(float(dt_s) - spec.dt_s) > 1e-12:
            raise ModelFileError(f"the decoder was trained at dt {spec.dt_s:g} s but the stream "
                                 f"steps at {dt_s:g} s; train a decoder at this step")
