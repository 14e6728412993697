"""The reference receiver's task decoders (skinhil/receiver/task_decoders.py) on spikes whose
answer is known: a centroid, a phase-locked frequency, the slip rule."""

from __future__ import annotations

import numpy as np

from skinhil.receiver.task_decoders import (
    force_n,
    frequency_hz,
    is_slip,
    locate_mm,
    sensor_xy_mm,
)


def test_locate_is_the_centroid_of_the_spiking_sensors() -> None:
    xy = sensor_xy_mm((6, 6))
    assert xy.shape == (338, 2) and np.allclose(xy.mean(axis=0), 0.0, atol=1e-9)
    near = np.flatnonzero(np.hypot(xy[:, 0] - 1.0, xy[:, 1] + 1.0) < 0.8)
    x, y = locate_mm(near, xy)
    assert abs(x - 1.0) < 0.3 and abs(y + 1.0) < 0.3
    assert locate_mm(np.zeros(0, dtype=np.int64), xy) == (0.0, 0.0)


def test_frequency_finds_the_rhythm_of_the_spikes() -> None:
    rng = np.random.default_rng(0)
    for hz in (50.0, 120.0, 300.0):
        cycles = np.arange(int(0.05 * hz))
        t_us = np.sort((cycles + 0.25) / hz * 1e6 + rng.normal(0, 100, cycles.size))
        t_us = np.concatenate([t_us, rng.uniform(0, 5e4, 3)])  # a few noise spikes
        assert abs(frequency_hz(np.sort(t_us).astype(np.int64)) - hz) <= 0.1 * hz
    # on the busiest channels: noise spread over many others is left out
    t_us = np.concatenate([np.arange(25) / 100.0 * 1e6 + rng.normal(0, 300, 25),
                           rng.uniform(0, 2.5e5, 100)])
    addr = np.concatenate([np.full(25, 7), rng.integers(20, 338, 100)])
    order = np.argsort(t_us)
    assert abs(frequency_hz(t_us[order].astype(np.int64), addr[order]) - 100.0) <= 2.0


def test_force_is_a_line_of_spikes_and_slip_needs_a_touch() -> None:
    assert force_n(10) != force_n(30) and min(force_n(0), force_n(10**6)) >= 0.0
    assert not is_slip(100_000, None)
    assert is_slip(300_000, 100_000) and not is_slip(700_000, 100_000)
