"""The host's estimate of the board's clock, from when board-stamped data arrive.

Every received item with a board time ``t`` (µs) that arrived at host monotonic time ``h``
(s) bounds the offset ``h − t`` from above by the link delay: the estimate is the smallest
such offset seen, relaxed upward by ``RELAX_PER_S`` per second so a board that falls
behind real time is followed. ``board_now_us()`` is then the board time the host believes
has been reached (a lower bound while the link delay is at least its minimum).
"""

from __future__ import annotations

import math
import time

RELAX_PER_S = 1e-3
"""Upward drift (s per s) of the offset estimate, so a slower board is followed."""


class BoardClock:
    """Map host monotonic time (s) ↔ board time (µs)."""

    def __init__(self) -> None:
        self.offset_s = math.inf
        self._last_update_s = 0.0

    @property
    def synced(self) -> bool:
        """Whether any board-stamped item has been seen."""
        return math.isfinite(self.offset_s)

    def observe(self, board_t_us: int, host_s: float | None = None) -> None:
        """A board-stamped item (time ``board_t_us``) arrived at host time ``host_s``."""
        h = time.monotonic() if host_s is None else host_s
        if self.synced:
            self.offset_s += RELAX_PER_S * max(0.0, h - self._last_update_s)
        self._last_update_s = h
        self.offset_s = min(self.offset_s, h - board_t_us * 1e-6)

    def board_now_us(self, host_s: float | None = None) -> int | None:
        """Board time (µs) estimated now; None before any observation."""
        if not self.synced:
            return None
        h = time.monotonic() if host_s is None else host_s
        return int((h - self.offset_s) * 1e6)

    def host_time_s(self, board_t_us: int) -> float | None:
        """Host monotonic time (s) at which the board was at ``board_t_us``."""
        return None if not self.synced else board_t_us * 1e-6 + self.offset_s
