"""The board's event FIFO between the neurons and the link, with its drop policy.

A ring buffer of :data:`skinhil.events.EVENT_DTYPE` records of fixed capacity (events), like
the RAM buffer of a microcontroller. Bursts are absorbed up to the capacity.

Drop policy (tail drop): when a block of new events does not fit, the events that fit are
kept in time order and the rest of the block — the newest — are dropped and counted as
``fifo_full``. Events already queued are never discarded to make room, so the stream the
receiver gets is always the oldest events, without holes inside what was queued.
"""

from __future__ import annotations

import numpy as np

from skinhil.events import EVENT_DTYPE


class EventFifo:
    """Fixed-capacity FIFO of events (``capacity`` events); see module docstring for drops."""

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"FIFO capacity must be >= 1 event, got {capacity!r}")
        self.capacity = int(capacity)
        self._buf = np.zeros(self.capacity, dtype=EVENT_DTYPE)
        self._head = 0  # index of the oldest event
        self._len = 0

    def __len__(self) -> int:
        return self._len

    @property
    def free(self) -> int:
        """Room left (events)."""
        return self.capacity - self._len

    def push(self, events: np.ndarray) -> int:
        """Append ``events`` (oldest first); return how many did not fit and were dropped."""
        n = min(len(events), self.free)
        if n:
            tail = (self._head + self._len) % self.capacity
            first = min(n, self.capacity - tail)
            self._buf[tail:tail + first] = events[:first]
            if n > first:
                self._buf[:n - first] = events[first:n]
            self._len += n
        return len(events) - n

    def peek_time_us(self) -> int | None:
        """Timestamp (µs) of the oldest queued event, or None if empty."""
        return int(self._buf["t"][self._head]) if self._len else None

    def time_at(self, i: int) -> int:
        """Timestamp (µs) of the ``i``-th oldest queued event (0-based)."""
        if not 0 <= i < self._len:
            raise IndexError(f"FIFO index {i} outside 0..{self._len - 1}")
        return int(self._buf["t"][(self._head + i) % self.capacity])

    def count_before(self, t_us: int) -> int:
        """How many queued events have ``t < t_us`` (queued events are in time order)."""
        first = min(self._len, self.capacity - self._head)
        seg = self._buf["t"][self._head:self._head + first]
        n = int(np.searchsorted(seg, t_us, side="left"))
        if n < first or self._len == first:
            return n
        return n + int(np.searchsorted(self._buf["t"][:self._len - first], t_us, side="left"))

    def peek(self, n: int) -> np.ndarray:
        """The up to ``n`` oldest events (a new array), left in the FIFO."""
        n = min(int(n), self._len)
        first = min(n, self.capacity - self._head)
        out = np.empty(n, dtype=EVENT_DTYPE)
        out[:first] = self._buf[self._head:self._head + first]
        if n > first:
            out[first:] = self._buf[:n - first]
        return out

    def pop(self, n: int) -> np.ndarray:
        """Remove and return up to ``n`` oldest events (a new array)."""
        out = self.peek(n)
        self._head = (self._head + len(out)) % self.capacity
        self._len -= len(out)
        return out

    def clear(self) -> int:
        """Empty the FIFO; return how many events were discarded."""
        n = self._len
        self._head = 0
        self._len = 0
        return n
