"""The PSP filter is eq. 12, exactly, online and offline."""

import numpy as np

from skinhil import PSPFilterBank, PSPParams, psp_kernel


def test_impulse_response_is_eq12() -> None:
    dt = 1e-4
    bank = PSPFilterBank(1, dt)
    raster = np.zeros((2000, 1))
    raster[0, 0] = 1
    y = bank.filter(raster)[:, 0]
    t_ms = np.arange(2000) * dt * 1e3
    p = PSPParams()
    eq12 = p.tau_m_ms / (p.tau_d_ms - p.tau_r_ms) * (np.exp(-t_ms / 4.0) - np.exp(-t_ms / 12.5))
    np.testing.assert_allclose(y, eq12, rtol=0, atol=1e-9)
    np.testing.assert_allclose(psp_kernel(t_ms / 1e3), eq12, rtol=0, atol=1e-12)


def test_peak_and_area() -> None:
    t = np.arange(0, 0.3, 1e-6)
    a = psp_kernel(t)
    assert abs(a.max() - 1.0) < 0.01
    assert abs(t[a.argmax()] * 1e3 - 6.7) < 0.1
    assert abs(np.trapezoid(a, t * 1e3) - 21.3) < 0.01
    assert psp_kernel(-1e-3) == 0.0


def test_online_equals_offline_in_any_chunking() -> None:
    rng = np.random.default_rng(3)
    counts = (rng.random((700, 5)) < 0.05).astype(float)
    offline = PSPFilterBank(5, 1e-4).filter(counts)
    by_step = PSPFilterBank(5, 1e-4)
    online = np.array([by_step.step(c) for c in counts])
    by_block = PSPFilterBank(5, 1e-4)
    blocks = np.concatenate([by_block.step_block(counts[i:i + 37]) for i in range(0, 700, 37)])
    np.testing.assert_allclose(online, offline, atol=1e-12)
    np.testing.assert_allclose(blocks, offline, atol=1e-12)


def test_event_driven_steps_equal_the_dense_filter_bit_for_bit() -> None:
    """``step_events`` (spikes as events, PSP written only where asked) gives the values of
    ``step_block`` on the same per-step counts exactly, several spikes of a channel in one
    step included, whatever the chunks and the rows asked."""
    rng = np.random.default_rng(3)
    n_steps, n = 700, 40
    steps = np.sort(rng.integers(0, n_steps, 900))
    chans = rng.integers(0, n, steps.size)
    chans[1::7] = chans[::7][: chans[1::7].size]  # repeats: two spikes of one channel, one step
    steps[1::7] = steps[::7][: steps[1::7].size]
    order = np.argsort(steps, kind="stable")
    steps, chans = steps[order], chans[order]
    counts = np.zeros((n_steps, n))
    np.add.at(counts, (steps, chans), 1.0)
    assert counts.max() >= 2
    dense = PSPFilterBank(n, 1e-4).step_block(counts)
    bank = PSPFilterBank(n, 1e-4)
    got = np.full((n_steps, n), np.nan)
    first = 0
    for size in (1, 13, 250, 36, 400):
        end = min(n_steps, first + size)
        sel = (steps >= first) & (steps < end)
        # ask for the chunk's rows from its second step on (the first stays unwritten)
        bank.step_events(end - first, steps[sel] - first, chans[sel], got[first + 1:end], 1)
        first = end
    assert first == n_steps
    written = np.ones(n_steps, bool)
    written[[0, 1, 14, 264, 300]] = False
    assert np.array_equal(got[written], dense[written])
    assert np.isnan(got[~written]).all()
