"""A receiver that fell behind catches up in bounded blocks (``MAX_BLOCK_STEPS``).

Reading a backlog of seconds at once must cost per second of stream what keeping up does:
inside user-mode Linux every fresh page is a round trip to the host, and 1 s blocks (27 MB
of PSP values each, fresh memory every time) took 1.24 s per 1 s of backlog, so the answer
loop's receiver, once behind, fell further behind (``benchmarks/bench_receiver_backlog.py``).
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

import skinhil
from skinhil.model.psp import PSPFilterBank, PSPParams
from skinhil.model.sensor import SkinSensor
from skinhil.receiver.online import OnsetWindows, Window

DT_S = 1e-4
DT_US = 100
WINDOW_STEPS = 500
BACKLOG_PEAK_BYTES = 40e6
"""Most memory catching up on the whole 3.9 s stream at once may hold at its peak, the
windows it returns included (9 of 1.35 MB): 27 MB in 0.1 s blocks, 165 MB in 1 s blocks."""


@pytest.fixture(scope="module")
def stream() -> tuple[np.ndarray, int, int]:
    """Events of 8 direction stimuli at 10 dB, their step count and channel count."""
    schedule = skinhil.random_schedule(skinhil.direction_conditions(), 8, rest_s=0.25,
                                       seed=4, lead_s=0.1)
    sensor = SkinSensor(dt_s=DT_S, snr_db=10.0, seed=1)
    n = int(math.ceil((schedule.duration_s + 0.05) / DT_S))
    _, spikes = sensor.advance_schedule(schedule, n)
    return sensor.events(spikes, 0), n, spikes.shape[1]


def _play(stream: tuple[np.ndarray, int, int], chunk_steps: int) -> tuple[list[Window], int]:
    """The windows of ``stream`` received in chunks of ``chunk_steps``; the largest memory
    peak (bytes) of one ``advance``."""
    events, n, n_channels = stream
    windows = OnsetWindows(DT_S, n_channels, PSPParams(), WINDOW_STEPS)
    out: list[Window] = []
    peak = 0
    for first in range(0, n, chunk_steps):
        end = min(n, first + chunk_steps)
        windows.push(events[(events["t"] >= first * DT_US) & (events["t"] < end * DT_US)])
        tracemalloc.start()
        try:
            out += windows.advance(end * DT_US)
            peak = max(peak, tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
    return out, peak


@pytest.fixture(scope="module")
def live(stream: tuple[np.ndarray, int, int]) -> list[Window]:
    """The windows of a receiver keeping up (20 ms chunks)."""
    return _play(stream, 200)[0]


def test_a_backlog_read_at_once_gives_the_windows_of_a_receiver_keeping_up_in_bounded_memory(
        stream: tuple[np.ndarray, int, int], live: list[Window]) -> None:
    behind, peak = _play(stream, stream[1])  # the whole stream at once
    assert len(live) >= 6  # the comparison is not vacuous
    assert [(w.detect_step, w.start_step) for w in behind] == [
        (w.detect_step, w.start_step) for w in live]
    for a, b in zip(live, behind, strict=True):
        assert np.array_equal(a.psp, b.psp)
    assert peak <= BACKLOG_PEAK_BYTES, f"{peak / 1e6:.1f} MB"


def test_the_windows_hold_the_dense_filters_values_bit_for_bit(
        stream: tuple[np.ndarray, int, int], live: list[Window]) -> None:
    """The receiver filters event by event and writes only its windows: each window is the
    dense eq. 12 filter of the whole stream's per-step counts over the window's steps,
    exactly (zero before the stream began)."""
    events, _, n_channels = stream
    assert len(live) >= 6
    last = max(w.start_step for w in live) + WINDOW_STEPS
    counts = np.zeros((last, n_channels))
    steps = events["t"] // DT_US
    keep = steps < last
    np.add.at(counts, (steps[keep], events["addr"][keep].astype(np.int64)), 1.0)
    dense = PSPFilterBank(n_channels, DT_S, PSPParams()).step_block(counts)
    for w in live:
        lo = max(w.start_step, 0)
        assert np.array_equal(w.psp[lo - w.start_step:], dense[lo:w.start_step + WINDOW_STEPS])
        assert not w.psp[:lo - w.start_step].any()
