"""The neuron noise's generator (skinhil/model/rng.py): counter-based words, Box-Muller in
float32 (the C kernel, skinhil/model/normals).

Checks that the normals are standard normal (density bin by bin, tails, variance), that they are
independent between channels, steps, trials and the two halves of a word, that a draw depends
on the seed's key and the step alone (not on how the steps are split into calls, nor on the
threads), and that the neurons' kernel adds exactly :func:`fill_normals`' numbers.
"""

import math

import numba
import numpy as np
import pytest
from scipy import stats

from skinhil import NeuronPopulation
from skinhil.model.normals import fill_normals
from skinhil.model.rng import TAIL_BOUND, seed_keys


def _grid(keys: np.ndarray, first_step: int, n_steps: int) -> np.ndarray:
    # (n_steps, channels, 2) normals: the pair of every key at every step, as float64
    out = np.empty((n_steps, 2, keys.shape[0]), np.float32)
    for k in range(n_steps):
        fill_normals(np.ascontiguousarray(keys), first_step + k, out[k, 0], out[k, 1])
    return out.transpose(0, 2, 1).astype(np.float64)


def _check_standard_normal(z: np.ndarray) -> None:
    assert stats.kstest(z, "norm").pvalue > 1e-3
    assert abs(z.mean()) < 5 / math.sqrt(z.size)
    assert abs(z.var() - 1) < 5 * math.sqrt(2 / z.size)
    # the density bin by bin (0.025 wide over ±4.5)
    edges = np.concatenate([[-np.inf], np.linspace(-4.5, 4.5, 361), [np.inf]])
    seen, _ = np.histogram(z, edges)
    expected = np.diff(stats.norm.cdf(edges)) * z.size
    assert stats.chisquare(seen, expected * seen.sum() / expected.sum()).pvalue > 1e-3
    assert np.abs(z).max() <= TAIL_BOUND
    for x in (3.5, 4.2):
        tail = (np.abs(z) > x).sum()
        mean = 2 * stats.norm.sf(x) * z.size
        assert abs(tail - mean) < 4 * np.sqrt(mean), x


def test_normals_across_channels_are_standard_normal() -> None:
    _check_standard_normal(_grid(seed_keys(11, 1_000_000), 7, 1).ravel())


def test_normals_of_one_channel_over_steps_are_standard_normal() -> None:
    z = _grid(seed_keys(12, 4), 0, 250_000)  # 4 channels x 250,000 steps x 2
    _check_standard_normal(z.ravel())


def test_independent_between_channels_steps_trials_and_halves() -> None:
    """Correlations of z and of z² (a dependence of the variance) between neighbouring
    channels, consecutive steps, two trials' same channel and the two halves of a word, over
    600,000 pairs: each |r| within 5 standard errors of 0."""
    keys = seed_keys(13, (2, 2000))
    a = _grid(keys[0], 1000, 300)  # (steps, channels, 2)
    b = _grid(keys[1], 1000, 300)
    pairs = {
        "channels": (a[:, :-1, 0], a[:, 1:, 0]),
        "steps": (a[:-1, :, 0], a[1:, :, 0]),
        "steps, u": (a[:-1, :, 1], a[1:, :, 1]),
        "trials": (a[..., 0], b[..., 0]),
        "halves": (a[..., 0], a[..., 1]),
        "halves across steps": (a[:-1, :, 0], a[1:, :, 1]),
    }
    for name, (x, y) in pairs.items():
        for power in (1, 2):
            r = np.corrcoef(x.ravel() ** power, y.ravel() ** power)[0, 1]
            assert abs(r) < 5 / math.sqrt(x.size), (name, power, r)


def test_seeding() -> None:
    assert np.array_equal(seed_keys(5, (3, 100)), seed_keys(5, (3, 100)))
    assert np.array_equal(seed_keys(np.random.SeedSequence(5), 40), seed_keys(5, 40))
    assert len(np.unique(seed_keys(5, 10_000))) == 10_000
    assert not np.array_equal(seed_keys(5, 100), seed_keys(6, 100))
    pops = [NeuronPopulation(50, snr_db=10.0, seed=s, batch=2) for s in (1, 1, 2)]
    streams = [p.step_block(np.full((200, 50), 0.02), 1e-4) for p in pops]
    assert np.array_equal(streams[0], streams[1]) and not np.array_equal(streams[0], streams[2])
    assert not np.array_equal(streams[0][:, 0], streams[0][:, 1])  # each trial its own noise


@pytest.mark.parametrize("threads", [1, 2])
def test_the_kernel_adds_the_normals_of_every_channel(threads: int) -> None:
    """Three steps of 2 trials x 2,600 channels (two whole blocks of 1,024 and a part) from
    a state that does not spike: after each step v and u are Euler's plus σ times the pair of
    :func:`fill_normals` of the channel's key at that step, bit for bit."""
    if threads > numba.config.NUMBA_NUM_THREADS:  # type: ignore[attr-defined]
        pytest.skip("needs two numba threads")
    batch, n, dt_ms, snr_db = 2, 2600, 0.1, 10.0
    rng = np.random.default_rng(8)
    pop = NeuronPopulation(n, snr_db=snr_db, seed=21, batch=batch, threads=threads)
    pop.v[:] = rng.uniform(-80, -60, (batch, n))
    pop.u[:] = rng.uniform(-16, -10, (batch, n))
    current = rng.uniform(-0.01, 0.01, (3, n))
    sigma = math.sqrt(10 ** (-snr_db / 10) * dt_ms)
    keys = pop.kernel_operands().keys
    v, u = pop.v.copy(), pop.u.copy()
    for k in range(3):
        assert not pop.step_block(current[k:k + 1], dt_ms * 1e-3).any()
        z = np.stack([_grid(keys[bb], k, 1)[0] for bb in range(batch)])  # (batch, n, 2)
        v, u = (v + dt_ms * (0.04 * v * v + 5.0 * v + 140.0 - u + 500.0 * current[k]),
                u + dt_ms * 0.02 * (0.2 * v - u))
        v = v + sigma * z[..., 0]
        u = u + sigma * z[..., 1]
        assert np.array_equal(pop.v, v) and np.array_equal(pop.u, u), k


def test_a_draw_depends_on_the_step_alone() -> None:
    """The same spikes whether 60 steps run in one call, in calls of 1, 7 and 52 steps, or on
    two threads; restoring the streams' position draws the same noise again."""
    n = 2100
    current = np.random.default_rng(9).uniform(0.0, 0.04, (60, n))
    whole = NeuronPopulation(n, snr_db=0.0, seed=4).step_block(current, 1e-4)
    assert whole.sum() > 100
    split = NeuronPopulation(n, snr_db=0.0, seed=4)
    parts = [split.step_block(current[a:b], 1e-4) for a, b in ((0, 1), (1, 8), (8, 60))]
    assert np.array_equal(np.concatenate(parts), whole)
    if numba.config.NUMBA_NUM_THREADS >= 2:  # type: ignore[attr-defined]
        two = NeuronPopulation(n, snr_db=0.0, seed=4, threads=2)
        assert np.array_equal(two.step_block(current, 1e-4), whole)
    again = NeuronPopulation(n, snr_db=0.0, seed=4)
    streams = again.noise_streams()
    first = again.step_block(current[:30], 1e-4)
    again.reset()
    again.restore_noise_streams(streams)
    assert np.array_equal(again.step_block(current[:30], 1e-4), first)
    assert np.array_equal(first, whole[:30])
