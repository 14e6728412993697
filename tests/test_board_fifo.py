"""The board's event FIFO and its accounting: tail drop, wrap-around, generated = sent +
dropped + queued."""

from __future__ import annotations

import numpy as np
import pytest

from firmware_sim.counters import DROP_REASONS, BoardCounters
from firmware_sim.fifo import EventFifo
from skinhil.events import make_events


def _events(t_us: list[int]) -> np.ndarray:
    t = np.asarray(t_us, dtype=np.int64)
    return make_events(t, (t // 100) % 338)


def test_tail_drop_keeps_the_oldest_and_drops_the_newest_of_a_block() -> None:
    fifo = EventFifo(5)
    assert fifo.push(_events([0, 100, 200])) == 0
    dropped = fifo.push(_events([300, 400, 500, 600]))
    assert dropped == 2 and len(fifo) == 5 and fifo.free == 0
    assert fifo.pop(10)["t"].tolist() == [0, 100, 200, 300, 400]
    assert len(fifo) == 0 and fifo.peek_time_us() is None


def test_queued_events_survive_wrap_around_in_time_order() -> None:
    fifo = EventFifo(4)
    fifo.push(_events([0, 100, 200]))
    fifo.pop(2)
    fifo.push(_events([300, 400, 500]))  # wraps: the ring's tail passes its end
    assert len(fifo) == 4
    assert [fifo.time_at(i) for i in range(4)] == [200, 300, 400, 500]
    assert fifo.count_before(400) == 2
    assert fifo.count_before(401) == 3
    assert fifo.count_before(10_000) == 4
    with pytest.raises(IndexError):
        fifo.time_at(4)
    out = fifo.pop(4)
    assert out["t"].tolist() == [200, 300, 400, 500]
    assert out["addr"].tolist() == [2, 3, 4, 5]


def test_clear_reports_what_it_discarded() -> None:
    fifo = EventFifo(8)
    fifo.push(_events([1, 2, 3]))
    assert fifo.clear() == 3
    assert len(fifo) == 0


def test_accounting_holds_for_random_traffic() -> None:
    """Random pushes, pops, stops and link losses: generated = sent + dropped + queued."""
    rng = np.random.default_rng(7)
    fifo, counts = EventFifo(64), BoardCounters()
    t = 0
    for _ in range(2000):
        n = int(rng.integers(0, 40))
        block = _events(list(range(t, t + 100 * n, 100)))
        t += 100 * n
        counts.generated += n
        what = rng.random()
        if what < 0.05:
            counts.drop("stopped", n)
        elif what < 0.07:
            counts.drop("link_down", n + fifo.clear())
        else:
            counts.drop("fifo_full", fifo.push(block))
        counts.sent += len(fifo.pop(int(rng.integers(0, 30))))
        assert counts.generated == counts.sent + counts.dropped + len(fifo)
    counts.drop("shutdown", fifo.clear())
    assert counts.generated == counts.sent + counts.dropped
    assert set(counts.dropped_by) == set(DROP_REASONS)
    assert all(counts.dropped_by[r] > 0 for r in ("fifo_full", "stopped", "link_down"))


def test_capacity_must_be_positive() -> None:
    with pytest.raises(ValueError, match="capacity"):
        EventFifo(0)
