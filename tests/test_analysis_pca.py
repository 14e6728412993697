"""PCA measures on data with known answers."""

import math

import numpy as np
import pytest

from skinhil.analysis import (
    area_between,
    information_measures,
    n_components_for,
    phase_pca,
    variance_explained,
)
from skinhil.analysis.pca import signal_information_ratio
from skinhil.analysis.phases import PhaseWindows, phase_samples


def low_rank(n: int, d: int, rank: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, rank)) @ rng.normal(size=(rank, d))


@pytest.mark.parametrize("rank", [1, 3, 7])
def test_npc_of_known_rank_with_equal_variances(rank: int) -> None:
    # orthonormal directions, equal variances: every component is needed for 99%
    rng = np.random.default_rng(rank)
    q, _ = np.linalg.qr(rng.normal(size=(20, rank)))
    scores = rng.normal(size=(4000, rank))
    chol = np.linalg.cholesky(np.atleast_2d(np.cov(scores.T)))
    scores = (scores - scores.mean(0)) @ np.linalg.inv(chol).T
    curve = variance_explained(scores @ q.T + 5.0)
    assert n_components_for(curve) == rank
    np.testing.assert_allclose(curve[rank - 1:], 1.0, atol=1e-9)
    np.testing.assert_allclose(curve[:rank], np.arange(1, rank + 1) / rank, atol=1e-9)


def test_npc_of_dominant_direction() -> None:
    rng = np.random.default_rng(0)
    x = np.outer(rng.normal(size=500), np.ones(10)) * 100 + rng.normal(size=(500, 10)) * 0.01
    assert n_components_for(variance_explained(x)) == 1
    assert n_components_for(variance_explained(low_rank(300, 12, 5, 1)), 1.0) == 5


def test_area_between_curves() -> None:
    a = np.array([0.5, 1.0, 1.0])
    b = np.array([1.0, 1.0, 1.0])
    # the paper's sign: sum(c_ind - c_post), negative when the indentation needs more PCs
    assert area_between(a, b) == pytest.approx(-0.5)
    assert area_between(b, a) == pytest.approx(0.5)
    assert area_between(np.array([0.25, 0.5, 0.75, 1.0]), np.array([1.0])) == pytest.approx(-1.5)


def test_sir_known_values() -> None:
    t = np.linspace(0, 1, 1000, endpoint=False)
    sine = np.sin(2 * np.pi * 5 * t)  # mean |z| = 2/π, std = 1/√2
    offset = 2.0 + sine  # mean |z| = 2, std = 1/√2
    z = np.stack([sine, offset, offset], axis=1)
    expected = np.mean([2 / np.pi * np.sqrt(2), 2 * np.sqrt(2), 2 * np.sqrt(2)])
    assert signal_information_ratio(z) == pytest.approx(expected, rel=1e-3)
    assert math.isnan(signal_information_ratio(np.ones((5, 3))))


def test_silent_phase_is_nan() -> None:
    pca = phase_pca(np.zeros((10, 4)))
    assert math.isnan(pca.npc99) and math.isnan(pca.sir)


def test_information_measures_phases() -> None:
    # indentation: 3 independent sensor patterns; post: a single pattern
    rng = np.random.default_rng(5)
    dt, n = 0.01, 50
    ind = rng.normal(size=(2, n, 3)) @ np.eye(3, 6)
    post = rng.normal(size=(2, n, 1)) @ np.ones((1, 6))
    m = information_measures(np.concatenate([ind, post], axis=1), dt,
                             PhaseWindows((0.0, 0.5), (0.5, 1.0)))
    assert (m.npc99_ind, m.npc99_post, m.npc_ratio) == (3.0, 1.0, 3.0)
    assert m.area < -0.5
    w_ind, w_post = PhaseWindows((0.0, 0.5), (0.5, 1.0)).steps(dt)
    assert (w_ind.start, w_ind.stop, w_post.stop) == (0, 50, 100)
    assert phase_samples(np.zeros((2, 100, 6)), w_post).shape == (100, 6)
