"""The receiver's estimate of board time: follows a board slower than real time, and is
fed only by items that come in stream order."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import protocols
from skinhil.events import make_events
from skinhil.receiver import Receiver, WindowDecoder
from skinhil.receiver.clock import BoardClock
from skinhil.receiver.training import train_decoder
from skinhil.transports import PtyMasterTransport


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


@pytest.fixture(scope="module")
def receiver_parts():
    decoder, _ = train_decoder(math.inf, reps=5, seed=0, rest_s=0.05)
    link, slave = PtyMasterTransport.open_pair()
    yield WindowDecoder(decoder), link
    link.shutdown()
    os.close(slave)


def _status(t_us: int, queued: int) -> protocols.Status:
    return protocols.Status(t_us=t_us, events_generated=1000 + queued, events_sent=1000,
                            events_dropped=0, events_queued=queued, late_ticks=0, rx_errors=0,
                            running=True)


@pytest.mark.parametrize("queued", [0, 400])
def test_a_status_ahead_of_queued_events_does_not_move_board_time(receiver_parts, queued):
    """A saturated board stamps its status ahead of the events still in its FIFO: such a
    status must not tell the receiver those steps are complete (their events would all be
    late); one sent with nothing queued does."""
    decoder, link = receiver_parts
    receiver = Receiver(link, decoder)
    enc = protocols.SerialEncoder()
    events = make_events(np.arange(500_000, 900_000, 1000), np.arange(400) % 338)
    head = enc.events(events[:0], 500_000) + enc.status(_status(1_000_000, queued))
    receiver.feed(head, 10.0)
    known = receiver.known_board_time_us(10.0)
    receiver.feed(enc.events(events, 1_000_000), 10.05)
    if queued:
        assert known < 500_000
        assert receiver.classifier.late_events == 0
    else:
        assert known >= 1_000_000 - receiver.params.guard_s * 1e6
