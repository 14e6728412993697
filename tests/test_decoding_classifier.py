"""DirectionDecoder: scikit-learn conventions, separable data, agreement with SVC."""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from skinhil.decoding import DirectionDecoder, FeatureSpec, cross_validate
from skinhil.errors import ConfigError

SPEC = FeatureSpec(dt_s=1e-3, window_s=0.004, bin_s=0.002, n_channels=5)  # 10 features


def toy(n_per_class: int, n_classes: int, sep: float, seed: int) -> tuple:
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(n_classes, SPEC.n_features)) * sep
    y = np.repeat(np.arange(n_classes), n_per_class)
    x = centres[y] + rng.normal(size=(y.size, SPEC.n_features))
    return x, y


def test_fit_returns_self_and_learned_attributes() -> None:
    x, y = toy(20, 3, 5.0, 0)
    dec = DirectionDecoder(SPEC)
    assert dec.fit(x, y) is dec
    assert dec.coef_.shape == (3, SPEC.n_features) and dec.intercept_.shape == (3,)
    assert list(dec.classes_) == [0, 1, 2] and dec.n_features_in_ == SPEC.n_features
    assert clone(dec).get_params()["spec"] == SPEC


def test_separable_toy_set_is_decoded_perfectly() -> None:
    x, y = toy(30, 9, 10.0, 1)
    cv = cross_validate(DirectionDecoder(SPEC), x, y, folds=5, repeats=2, seed=0)
    assert cv.accuracy == pytest.approx(1.0)
    assert np.array_equal(cv.confusion, np.diag(np.full(9, 2 * 30)))


def test_decisions_match_scikit_learn_svc() -> None:
    x, y = toy(25, 4, 0.7, 2)
    dec = DirectionDecoder(SPEC).fit(x, y)
    z = StandardScaler().fit(x).transform(x)
    ref = SVC(kernel="linear", break_ties=True).fit(z, y)
    np.testing.assert_allclose(dec.decision_function(x), ref.decision_function(z), atol=1e-9)
    assert np.array_equal(dec.predict(x), ref.predict(z))


def test_two_classes_sign_convention() -> None:
    x, y = toy(25, 2, 3.0, 3)
    dec = DirectionDecoder(SPEC).fit(x, y)
    scores = dec.decision_function(x)
    assert scores.shape == (50,)
    assert np.array_equal(dec.predict(x), dec.classes_[(scores > 0).astype(int)])
    assert dec.score(x, y) > 0.9


def test_bad_inputs_refused() -> None:
    x, y = toy(10, 2, 3.0, 4)
    with pytest.raises(ConfigError, match="expected"):
        DirectionDecoder(SPEC).fit(x[:, :-1], y)
    with pytest.raises(ConfigError, match="two classes"):
        DirectionDecoder(SPEC).fit(x, np.zeros(len(y)))
    with pytest.raises(ConfigError, match="not fitted"):
        DirectionDecoder(SPEC).predict(x)
    with pytest.raises(ConfigError, match="fewer than"):
        cross_validate(DirectionDecoder(SPEC), x[:12], y[:12], folds=5, repeats=1)
