"""The activity-only onset rule on simulated streams (no ground truth used by the rule)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import skinhil
from skinhil.model.sensor import SkinSensor
from skinhil.receiver import OnsetDetector, OnsetParams

DT_S = 1e-4


@pytest.fixture(scope="module")
def noise_free_stream() -> tuple[np.ndarray, list[int]]:
    """Population counts of 12 random direction stimuli without noise, and the onset steps."""
    schedule = skinhil.random_schedule(skinhil.direction_conditions(), 12, rest_s=0.05,
                                       seed=4, lead_s=0.1)
    sensor = SkinSensor(dt_s=DT_S, snr_db=math.inf)
    n = int(round((schedule.duration_s + 0.05) / DT_S))
    _, spikes = sensor.advance_schedule(schedule, n)
    onsets = [int(math.ceil(e.onset_s / DT_S - 1e-9)) for e in schedule.entries]
    return spikes.sum(axis=1), onsets


def test_every_noise_free_onset_is_found_within_15_ms(noise_free_stream):
    counts, onsets = noise_free_stream
    found = np.array(OnsetDetector(DT_S).process(counts))
    assert len(found) == len(onsets)
    delay = found - np.array(onsets)
    assert np.all(delay >= 0) and np.all(delay * DT_S <= 0.015)


def test_result_does_not_depend_on_chunking():
    # a 10 dB stream of 30 stimuli with short rests: onsets follow the noise baseline, whose
    # exclusion of the steps before each onset must not depend on where a chunk ended
    schedule = skinhil.random_schedule(skinhil.direction_conditions(), 30, rest_s=0.05,
                                       seed=5, lead_s=0.1)
    sensor = SkinSensor(dt_s=DT_S, snr_db=10.0, seed=2)
    _, spikes = sensor.advance_schedule(schedule, int(round(schedule.duration_s / DT_S)))
    counts = spikes.sum(axis=1)
    whole_detector = OnsetDetector(DT_S)
    whole = whole_detector.process(counts)
    assert len(whole) >= 20
    rng = np.random.default_rng(0)
    random_edges = np.sort(rng.choice(np.arange(1, len(counts)), 400, replace=False))
    for edges in (np.arange(10, len(counts), 10), random_edges):  # board ticks; anywhere
        det = OnsetDetector(DT_S)
        pieces: list[int] = []
        for chunk in np.split(counts, edges):
            pieces += det.process(chunk)
        assert pieces == whole
        assert det.threshold == whole_detector.threshold


def test_threshold_follows_the_noise_baseline():
    quiet, noisy = OnsetDetector(DT_S), OnsetDetector(DT_S)
    quiet.process(np.zeros(5000))
    noisy.process(np.random.default_rng(1).poisson(4.0, 5000))  # 4 spikes per step
    p = OnsetParams()
    assert quiet.threshold == pytest.approx(p.min_excess_spikes)
    window = round(p.window_s / DT_S)
    # mean window count 4·W, Poisson sd sqrt(4·W): threshold ≈ mean + z·sd
    assert noisy.threshold == pytest.approx(4 * window + p.z * math.sqrt(4 * window), rel=0.1)


def test_no_onset_in_a_silent_or_stationary_stream():
    assert OnsetDetector(DT_S).process(np.zeros(20000)) == []
    rng = np.random.default_rng(2)
    found = OnsetDetector(DT_S, OnsetParams(z=6.0)).process(rng.poisson(4.0, 20000))
    assert found == []
