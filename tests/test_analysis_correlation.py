"""Zero-lag normalised cross-correlation and the similarity matrix on known signals."""

import math

import numpy as np
import pytest

from skinhil import SkinModel
from skinhil.analysis import sensors_of_mass, similarity_matrix, zero_lag_ncc


def test_identical_orthogonal_opposite_proportional() -> None:
    t = np.linspace(0, 1, 400, endpoint=False)
    s = np.sin(2 * np.pi * 3 * t)
    c = np.cos(2 * np.pi * 3 * t)
    assert zero_lag_ncc(s, s) == pytest.approx(1.0)
    assert zero_lag_ncc(s, c) == pytest.approx(0.0, abs=1e-12)
    assert zero_lag_ncc(s, -s) == pytest.approx(-1.0)
    assert zero_lag_ncc(s, 7.5 * s) == pytest.approx(1.0)
    assert math.isnan(float(zero_lag_ncc(s, np.zeros_like(s))))


def test_similarity_matrix_means_over_sensors() -> None:
    t = np.linspace(0, 1, 400, endpoint=False)
    s, c = np.sin(2 * np.pi * 3 * t), np.cos(2 * np.pi * 3 * t)
    # sensor 0: stim 1 equals stim 0; sensor 1: stim 1 orthogonal to stim 0; sensor 2 silent
    r = np.zeros((3, t.size, 3))
    r[0, :, 0], r[0, :, 1] = s, s
    r[1, :, 0], r[1, :, 1] = s, c
    r[2, :, 0], r[2, :, 1] = -s, -s
    m = similarity_matrix(r)
    np.testing.assert_allclose(np.diag(m), 1.0)
    assert m[0, 1] == pytest.approx(0.5) and m[1, 0] == pytest.approx(0.5)
    assert m[0, 2] == pytest.approx(-1.0)


def test_sensors_of_m15() -> None:
    model = SkinModel()
    idx = sensors_of_mass(model.springs, 15)
    assert np.all(np.any(model.springs[idx] == 14, axis=1))
    others = np.setdiff1d(np.arange(model.n_springs), idx)
    assert not np.any(model.springs[others] == 14)
    # 4 grid neighbours, 2 diagonals of the cells M15 shares, 4 springs to layer 2
    assert idx.size == 10
