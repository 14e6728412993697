"""Izhikevich neurons: Euler reference, reset, noise variance, determinism."""

import math

import numpy as np
import pytest

from skinhil import IzhikevichParams, NeuronPopulation, events_to_raster, raster_to_events
from skinhil.errors import ConfigError
from skinhil.model.neurons import NoiseParams


def _euler_reference(current: float, n_steps: int, dt_ms: float) -> list[int]:
    """Plain Python transcription of the documented per-step order, no noise."""
    a, b, c, d, k = 0.02, 0.2, -65.0, 9.0, 500.0
    v, u = c, b * c
    spikes = []
    for step in range(n_steps):
        dv = 0.04 * v * v + 5 * v + 140 - u + k * current
        v, u = v + dt_ms * dv, u + dt_ms * a * (b * v - u)
        if v >= 30.0:
            spikes.append(step)
            v, u = c, u + d
    return spikes


@pytest.mark.parametrize("force_n", [0.01, 0.03, 0.1])
def test_matches_euler_reference(force_n: float) -> None:
    pop = NeuronPopulation(1)
    raster = pop.step_block(np.full((5000, 1), force_n), 1e-4)
    ours = list(np.flatnonzero(raster[:, 0]))
    assert ours == _euler_reference(force_n, 5000, 0.1)
    assert len(ours) > 3


def test_compression_inhibits() -> None:
    pop = NeuronPopulation(2)
    raster = pop.step_block(np.tile([0.05, -0.05], (5000, 1)), 1e-4)
    assert raster[:, 0].sum() > 5 and raster[:, 1].sum() == 0


def test_reset_rule() -> None:
    pop = NeuronPopulation(1)
    pop.v[:] = 29.0
    pop.u[:] = -10.0
    v_next = 29.0 + 0.1 * (0.04 * 29.0**2 + 5 * 29.0 + 140 + 10.0)
    u_next = -10.0 + 0.1 * 0.02 * (0.2 * 29.0 + 10.0)
    assert v_next >= 30
    spikes = pop.step_block(np.zeros((1, 1)), 1e-4)
    assert spikes[0, 0]
    assert pop.v[0, 0] == -65.0
    assert pop.u[0, 0] == pytest.approx(u_next + 9.0, abs=1e-12)


MEASURED = NoiseParams(definition="measured")


def test_measured_noise_variance_is_measured_awgn() -> None:
    """Option "measured", one step from a known state: σ² = mean(x²)/10^(SNR/10) (±3 %)."""
    snr_db, batch, n = 20.0, 300, 338
    rng = np.random.default_rng(0)
    v0 = rng.uniform(-80, -50, (batch, n))
    u0 = rng.uniform(-20, 0, (batch, n))
    clean = NeuronPopulation(n, batch=batch, noise=MEASURED)
    noisy = NeuronPopulation(n, snr_db=snr_db, seed=5, batch=batch, noise=MEASURED)
    for pop in (clean, noisy):
        pop.v[:] = v0
        pop.u[:] = u0
        spikes = pop.step_block(np.zeros((1, n)), 1e-4)
        assert not spikes.any()
    ratio = 10 ** (-snr_db / 10)
    for noisy_x, clean_x in ((noisy.v, clean.v), (noisy.u, clean.u)):
        expected = (clean_x**2).mean(axis=1) * ratio  # per trial
        z = (noisy_x - clean_x) / np.sqrt(expected)[:, None]
        # variance estimate over 101,400 samples has relative s.d. 0.44 %: 3 % is > 6 s.d.
        assert abs(z.var() - 1.0) < 0.03
        assert abs(z.mean()) < 0.02


def test_snr_inf_is_deterministic_and_seed_reproducible() -> None:
    force = np.random.default_rng(1).uniform(-0.05, 0.1, (2000, 20))
    a = NeuronPopulation(20, seed=1).step_block(force, 1e-4)
    b = NeuronPopulation(20, seed=2).step_block(force, 1e-4)
    assert np.array_equal(a, b)
    c = NeuronPopulation(20, snr_db=10, seed=1).step_block(force, 1e-4)
    d = NeuronPopulation(20, snr_db=10, seed=1).step_block(force, 1e-4)
    e = NeuronPopulation(20, snr_db=10, seed=2).step_block(force, 1e-4)
    assert np.array_equal(c, d) and not np.array_equal(c, e)


def test_events_round_trip() -> None:
    raster = np.random.default_rng(2).random((300, 338)) < 0.01
    ev = raster_to_events(raster, 1e-4, t0_us=5000)
    assert np.all(np.diff(ev["t"]) >= 0) and np.all(ev["t"] % 100 == 0)
    back = events_to_raster(ev, 300, 338, 1e-4, t0_us=5000)
    assert np.array_equal(back.astype(bool), raster)


def test_bad_input() -> None:
    with pytest.raises(ConfigError, match="SNR nan dB"):
        NeuronPopulation(3, snr_db=float("nan"))
    with pytest.raises(ConfigError, match="dt_s"):
        NeuronPopulation(3).step_block(np.zeros((2, 3)), 0.0)
    with pytest.raises(ConfigError, match="shape"):
        NeuronPopulation(3).step_block(np.zeros((2, 4)), 1e-4)
    with pytest.raises(ConfigError, match="c_mv"):
        IzhikevichParams(c_mv=40.0)
    with pytest.raises(ConfigError, match="whole number of microseconds"):
        raster_to_events(np.zeros((2, 2), bool), 1.5e-7)
    assert math.isinf(NeuronPopulation(1).snr_db)


def test_measured_runaway_noise_is_reset_and_counted() -> None:
    """Below ~24 dB the measured-power noise on u feeds itself; trials restart, never NaN."""
    low = NeuronPopulation(338, snr_db=10, seed=1, noise=MEASURED)
    spikes = low.step_block(np.zeros((5000, 338)), 1e-4)
    assert np.isfinite(low.v).all() and np.isfinite(low.u).all()
    assert low.blowups[0] > 0
    assert spikes[-1000:].any()  # still firing at the end: never silent for good
    high = NeuronPopulation(338, snr_db=30, seed=1, noise=MEASURED)
    high.step_block(np.zeros((5000, 338)), 1e-4)
    assert high.blowups[0] == 0


def test_raster_to_events_scans_every_byte() -> None:
    # the compiled scan skips 64-byte lines without a spike: against numpy's flat nonzero
    # on rasters whose spikes sit on line edges, in the tail after the last whole line, and
    # at every density from none to all
    rng = np.random.default_rng(4)
    for shape in ((10, 17866), (10, 338), (3, 7), (0, 338), (1, 1), (100, 65)):
        for density in (0.0, 1e-4, 0.02, 0.5, 1.0):
            raster = rng.random(shape) < density
            if raster.size:
                raster.flat[[0, raster.size - 1]] = True
                raster.flat[63::64] |= rng.random(raster.flat[63::64].shape) < 0.5
            events = raster_to_events(raster, 1e-4, t0_us=700)
            steps, addr = np.divmod(np.flatnonzero(raster), max(raster.shape[1], 1))
            assert np.array_equal(events["t"], 700 + 100 * steps)
            assert np.array_equal(events["addr"], addr)


def test_single_precision_forces_are_read_as_they_are() -> None:
    """step_block takes the leapfrog's single-precision forces without a double copy: the
    same spikes and membranes as the same values given in double precision, at 10 dB."""
    rng = np.random.default_rng(5)
    forces = rng.normal(0.004, 0.01, (400, 64)).astype(np.float32)
    single, double = (NeuronPopulation(64, snr_db=10.0, seed=9) for _ in range(2))
    spikes = single.step_block(forces, 1e-4)
    assert spikes.any()
    assert np.array_equal(spikes, double.step_block(forces.astype(np.float64), 1e-4))
    assert np.array_equal(single.v, double.v) and np.array_equal(single.u, double.u)
