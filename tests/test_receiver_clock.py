"""The receiver's estimate of board time follows a board slower than real time."""

from __future__ import annotations

import numpy as np

from skinhil.receiver.clock import BoardClock


def feed(clock: BoardClock, rate: float, delays_s: np.ndarray, period_s: float) -> list[float]:
    """Items every ``period_s`` of host time from a board whose time runs at ``rate`` x host
    time, each delivered after its delay; returns estimate − true board time (s) per item."""
    errors = []
    for i, delay in enumerate(delays_s):
        h = i * period_s
        board_s = rate * (h - delay)  # the item was stamped when it left the board
        clock.observe(int(round(board_s * 1e6)), h)
        now = clock.board_now_us(h)
        assert now is not None
        errors.append(now * 1e-6 - rate * h)
    return errors


def test_real_time_board_is_estimated_by_its_fastest_delivery():
    rng = np.random.default_rng(0)
    delays = 0.001 + rng.exponential(0.005, 2000)
    clock = BoardClock()
    errors = np.array(feed(clock, 1.0, delays, 0.01))
    # never ahead of the board by more than the fastest delivery of the window
    assert errors.max() <= 0.0
    assert np.median(errors) > -0.0015


def test_board_at_half_real_time_is_followed():
    delays = np.full(2000, 0.002)
    clock = BoardClock(window_s=0.25)
    errors = np.array(feed(clock, 0.5, delays, 0.01))
    # the estimate drifts ahead by at most the lag accumulated over one window
    assert np.all(errors <= 0.5 * 0.25 + 1e-6)
    assert np.all(errors[-100:] >= -0.01)


def test_silence_keeps_the_estimate_running_on_the_host_clock():
    clock = BoardClock()
    assert clock.board_now_us(0.0) is None
    clock.observe(1_000_000, 10.0)
    assert clock.board_now_us(12.5) == 3_500_000
    host = clock.host_time_s(2_000_000)
    assert host is not None and abs(host - 11.0) < 1e-9
