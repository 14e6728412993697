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
