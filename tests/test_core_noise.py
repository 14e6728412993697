"""The default neuron noise: a step-invariant diffusion (σ·sqrt(dt/dt_ref)·N(0,1) per step).

Checks the three properties the noise definition promises (skinhil/model/neurons.py): the σ added
per step is the documented one, no SNR down to −10 dB runs away, and the spike statistics at
10 dB do not depend on the step.
"""

import math

import numpy as np
import pytest
from scipy import stats

from skinhil import NeuronPopulation, SkinModel
from skinhil.errors import ConfigError
from skinhil.model.neurons import NoiseParams
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import Schedule, ScheduledStimulus, builtin_catalog, direction_conditions


@pytest.mark.parametrize(("snr_db", "dt_ms"), [(10.0, 0.1), (10.0, 0.025), (0.0, 1.0),
                                               (-10.0, 0.05)])
def test_sigma_per_step_matches_definition(snr_db: float, dt_ms: float) -> None:
    """One step from the same state with and without noise: the increments on v and on u
    have variance 1 mV² · 10^(−SNR/10) · dt / 1 ms, are centred and are independent."""
    batch, n = 300, 338
    rng = np.random.default_rng(0)
    v0 = rng.uniform(-80, -50, (batch, n))
    u0 = rng.uniform(-20, 0, (batch, n))
    clean = NeuronPopulation(n, batch=batch)
    noisy = NeuronPopulation(n, snr_db=snr_db, seed=5, batch=batch)
    for pop in (clean, noisy):
        pop.v[:] = v0
        pop.u[:] = u0
        assert not pop.step_block(np.zeros((1, n)), dt_ms * 1e-3).any()
    sigma = math.sqrt(10 ** (-snr_db / 10) * dt_ms / 1.0)
    assert NoiseParams().sigma_per_step_mv(snr_db, dt_ms * 1e-3) == pytest.approx(sigma)
    zv = ((noisy.v - clean.v) / sigma).ravel()
    zu = ((noisy.u - clean.u) / sigma).ravel()
    for z in (zv, zu):
        # 101,400 samples: the variance estimate has relative s.d. sqrt(2/N) = 0.44 %, the
        # mean s.d. 0.0031; 3 % and 0.02 are both beyond 6 s.d.
        assert abs(z.var() - 1.0) < 0.03
        assert abs(z.mean()) < 0.02
    assert abs(np.corrcoef(zv, zu)[0, 1]) < 0.02


def test_snr_inf_adds_nothing() -> None:
    assert NoiseParams().sigma_per_step_mv(math.inf, 1e-4) == 0.0
    pop = NeuronPopulation(5, seed=1)
    pop.step_block(np.zeros((1000, 5)), 1e-4)
    assert np.all(pop.v == pop.v[0, 0]) and np.all(pop.u == pop.u[0, 0])


def _strongest_builtin() -> tuple[int, object]:
    """The built-in stimulus with the largest peak spring force (ties: catalogue order)."""
    cat = builtin_catalog()
    items = list(cat.values())
    forces = SkinModel().simulate_many([s for _, s in items], 0.3, 1e-4)
    return items[int(np.argmax(np.abs(forces).max(axis=(1, 2))))]


@pytest.mark.parametrize("snr_db", [-10.0, 0.0, 10.0, 30.0])
def test_no_runaway_over_10_s_of_the_strongest_stimulus(snr_db: float) -> None:
    """10 s of the strongest built-in stimulus back to back at dt 0.1 ms: state finite and
    within physiological range after every second, no trial reset, rates bounded (mean
    ≤ 100 Hz per channel, none above 500 Hz; the run-away measured-power noise made
    noise-driven bursts of ~2,700 Hz)."""
    sid, stim = _strongest_builtin()
    period = stim.end_s  # type: ignore[attr-defined]
    n = int(math.ceil(10.0 / period))
    schedule = Schedule(tuple(ScheduledStimulus(k * period, stim, sid)  # type: ignore[arg-type]
                              for k in range(n)))
    sensor = SkinSensor(dt_s=1e-4, snr_db=snr_db, seed=7)
    counts = np.zeros(sensor.model.n_springs)
    peak_force = 0.0
    for _ in range(10):
        springs, spikes = sensor.advance_schedule(schedule, 10_000)
        counts += spikes.sum(axis=0)
        peak_force = max(peak_force, float(np.abs(springs).max()))
        v, u = sensor.neurons.v, sensor.neurons.u
        assert np.isfinite(v).all() and np.isfinite(u).all()
        assert v.max() < 30.0 and v.min() > -200.0 and np.abs(u).max() < 200.0
    assert sensor.neurons.blowups.sum() == 0
    rates_hz = counts / 10.0
    assert rates_hz.mean() <= 100.0 and rates_hz.max() <= 500.0
    assert peak_force > 0.05 and counts.sum() > 0  # the press loads the sensors (N)


def _isi_cv(raster: np.ndarray) -> float:
    """ISI coefficient of variation pooled over the channels of one trial (n_steps, n)."""
    ch, steps = np.nonzero(raster.T)  # sorted by channel, then step
    isi = np.diff(steps)[np.diff(ch) == 0]
    return float(isi.std() / isi.mean())


def test_spike_statistics_do_not_depend_on_the_step() -> None:
    """10 dB, 0.3 N at 120°, 0.5 s, 40 independent trials per step (own seed per step): the
    pooled spike count and ISI CV per trial at dt 0.1, 0.05, 0.025 ms agree.

    Test: Welch's z on the per-trial means of each pair of steps; the trials are independent,
    so by the central limit theorem z is ~N(0, 1) when the step does not matter. Six
    comparisons at a family-wise false-alarm rate of 0.1 % (Bonferroni): |z| < 3.77. The
    tolerance this makes (~5 %) is checked to be below 10 % of the mean count, so a change like the
    ~40 % of the earlier measured-power noise between 0.1 and 0.05 ms would fail."""
    reps, duration_s = 40, 0.5
    stim = direction_conditions()[4]  # 120°, 0.3 N
    z_crit = stats.norm.isf(0.001 / 2 / 6)
    per_dt = {}
    for i, dt_s in enumerate((1e-4, 5e-5, 2.5e-5)):
        forces = SkinModel().simulate_many([stim], duration_s, dt_s)[0]
        pop = NeuronPopulation(forces.shape[1], snr_db=10.0, seed=np.random.SeedSequence(
            [2026, i]), batch=reps)
        spikes = pop.step_block(forces, dt_s)  # (n_steps, reps, n)
        counts = spikes.sum(axis=(0, 2)).astype(float)
        cvs = np.array([_isi_cv(spikes[:, r, :]) for r in range(reps)])
        per_dt[dt_s] = (counts, cvs)
    dts = list(per_dt)
    for a in range(3):
        for b in range(a + 1, 3):
            for k in range(2):
                xa, xb = per_dt[dts[a]][k], per_dt[dts[b]][k]
                se = math.sqrt(xa.var(ddof=1) / reps + xb.var(ddof=1) / reps)
                z = (xa.mean() - xb.mean()) / se
                assert abs(z) < z_crit, (dts[a], dts[b], ("count", "ISI CV")[k], z)
                if k == 0:
                    assert z_crit * se < 0.10 * xa.mean()
    assert per_dt[dts[0]][0].mean() > 100  # enough spikes for the statistics to mean something


def test_noise_params_are_checked() -> None:
    with pytest.raises(ConfigError, match="definition"):
        NoiseParams(definition="white")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="ref_step_ms"):
        NoiseParams(ref_step_ms=0.0)
    with pytest.raises(ConfigError, match="measured"):
        NoiseParams(definition="measured").sigma_per_step_mv(10.0, 1e-4)
