"""The host's estimate of the board's clock, from when board-stamped data arrive.

Every received item with a board time ``t`` (µs) that arrived at host monotonic time ``h``
(s) bounds the offset ``h − t`` from above by the link delay. The estimate is the smallest
such offset among the items of the last ``WINDOW_S`` seconds of host time (the newest item
always counts): short enough that a board running slower than real time (a loaded host,
user-mode Linux) is followed within ``WINDOW_S`` times its lag rate, long enough to take
the fastest delivery of several status/SYNC periods. Between items the estimate runs on
the host clock, so ``board_now_us()`` keeps advancing through a silent stream; when the
board stalls, it runs ahead by the stall, which the receiver's board-time guard absorbs.
"""

from __future__ import annotations

import math
import time
from collections import deque

WINDOW_S = 0.25
"""Host seconds of observations whose smallest offset is the estimate."""


class BoardClock:
    """Map host monotonic time (s) ↔ board time (µs)."""

    def __init__(self, window_s: float = WINDOW_S) -> None:
        self.window_s = float(window_s)
        self.offset_s = math.inf
        self._recent: deque[tuple[float, float]] = deque()
        """(host time s, offset s) with increasing offsets: a sliding-window minimum."""

    @property
    def synced(self) -> bool:
        """Whether any board-stamped item has been seen."""
        return math.isfinite(self.offset_s)

    def observe(self, board_t_us: int, host_s: float | None = None) -> None:
        """A board-stamped item (time ``board_t_us``) arrived at host time ``host_s``."""
        h = time.monotonic() if host_s is None else host_s
        offset = h - board_t_us * 1e-6
        recent = self._recent
        while recent and recent[-1][1] >= offset:
            recent.pop()
        recent.append((h, offset))
        while recent[0][0] < h - self.window_s:
            recent.popleft()
        self.offset_s = recent[0][1]

    def board_now_us(self, host_s: float | None = None) -> int | None:
        """Board time (µs) estimated now; None before any observation."""
        if not self.synced:
            return None
        h = time.monotonic() if host_s is None else host_s
        return int((h - self.offset_s) * 1e6)

    def host_time_s(self, board_t_us: int) -> float | None:
        """Host monotonic time (s) at which the board was at ``board_t_us``."""
        return None if not self.synced else board_t_us * 1e-6 + self.offset_s

    def wall_time_s(self, board_t_us: int) -> float | None:
        """Wall-clock time (s since the Unix epoch, ``time.time()``'s) at which the board was
        at ``board_t_us`` (µs): :meth:`host_time_s` moved to the wall clock by the host's
        current wall-minus-monotonic offset. ``wall_time_s(0)`` is when the board started
        (the start time of a recorded session); None before any observation."""
        host = self.host_time_s(board_t_us)
        return None if host is None else host + (time.time() - time.monotonic())
