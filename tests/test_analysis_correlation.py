"""Zero-lag normalised cross-correlation and the similarity matrix on known signals."""

import math

import numpy as np
import pytest

from skinhil import SkinModel
from skinhil.analysis import sensors_of_mass, similarity_matrix, zero_lag_ncc
from skinhil.analysis.correlation import correlation_index


def test_identical_orthogonal_opposite_proportional() -> None:
    t = np.linspace(0, 1, 400, endpoint=False)
    s = np.sin(2 * np.pi * 3 * t)
    c = np.cos(2 * np.pi * 3 * t)
    assert zero_lag_ncc(s, s) == pytest.approx(1.0)
    assert zero_lag_ncc(s, c) == pytest.approx(0.0, abs=1e-12)
    assert zero_lag_ncc(s, -s) == pytest.approx(-1.0)
    assert zero_lag_ncc(s, 7.5 * s) == pytest.approx(1.0)
    assert math.isnan(float(zero_lag_ncc(s, np.zeros_like(s))))


def test_similarity_index_over_all_sensors_clipped_at_zero() -> None:
    t = np.linspace(0, 1, 400, endpoint=False)
    s, c = np.sin(2 * np.pi * 3 * t), np.cos(2 * np.pi * 3 * t)
    r = np.zeros((5, t.size, 2))
    r[0, :, 0] = s               # stim 0: sensor 0 only
    r[1, :, 0] = 3.0 * s         # stim 1: the same pattern, three times stronger
    r[2, :, 0] = -s              # stim 2: the opposite pattern
    r[3, :, 1] = s               # stim 3: another sensor: uncorrelated with stim 0
    r[4, :, 0], r[4, :, 1] = s, c  # stim 4: stim 0 plus an orthogonal part of equal energy
    m = similarity_matrix(r)
    np.testing.assert_allclose(np.diag(m), 1.0)
    np.testing.assert_allclose(m, m.T)
    assert m[0, 1] == pytest.approx(1.0)
    assert m[0, 2] == 0.0 and m[0, 3] == pytest.approx(0.0, abs=1e-12)
    assert m[0, 4] == pytest.approx(1 / math.sqrt(2))
    assert math.isnan(correlation_index(r[0], np.zeros_like(r[0])))


def test_sensors_of_m15() -> None:
    model = SkinModel()
    idx = sensors_of_mass(model.springs, 15)
    assert np.all(np.any(model.springs[idx] == 14, axis=1))
    others = np.setdiff1d(np.arange(model.n_springs), idx)
    assert not np.any(model.springs[others] == 14)
    # 4 grid neighbours, 2 diagonals of the cells M15 shares, 4 springs to layer 2
    assert idx.size == 10
