"""A record of latenesses (s): a bounded ring of the latest, the maximum over all, and their
percentiles. The board's tick clock and the replayer each keep one."""

from __future__ import annotations

import numpy as np


class LatenessLog:
    """The last ``history`` latenesses (s), in order, and the largest of all recorded."""

    def __init__(self, history: int) -> None:
        self._lateness = np.zeros(history)
        self.count = 0
        """Latenesses recorded so far (kept or not)."""
        self.max_s = 0.0
        """The largest lateness recorded (s; 0 before any)."""

    def record(self, late_s: float) -> None:
        """Add one lateness (s)."""
        self._lateness[self.count % len(self._lateness)] = late_s
        self.count += 1
        if late_s > self.max_s:
            self.max_s = late_s

    def lateness_s(self, last: int | None = None) -> np.ndarray:
        """The kept latenesses (s), oldest first: all (at most ``history``), or only the
        ``last`` ones."""
        size = len(self._lateness)
        n = min(self.count, size if last is None else min(int(last), size))
        if n <= 0:
            return self._lateness[:0].copy()
        end = self.count % size
        if end == 0 and self.count:
            end = size
        start = end - n
        if start >= 0:
            return self._lateness[start:end].copy()
        return np.concatenate([self._lateness[start:], self._lateness[:end]])

    def percentiles_ms(self, qs: tuple[float, ...] = (50, 99),
                       last: int | None = None) -> dict[str, float]:
        """Percentiles of the kept latenesses (or the ``last`` ones) and the maximum over all,
        in ms (keys ``p50``, ``p99``, ``max``; 0 when none)."""
        lat = self.lateness_s(last)
        out = {f"p{q:g}": float(np.percentile(lat, q)) * 1e3 if lat.size else 0.0 for q in qs}
        out["max"] = self.max_s * 1e3
        return out
