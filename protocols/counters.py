"""Counter unwrapping and the status-based event loss accounting (SPEC.md §7)."""

from __future__ import annotations

import dataclasses
from typing import Any

from protocols.records import LinkCounters, Status

STATUS_COUNTERS = ("events_generated", "events_sent", "events_dropped", "late_ticks",
                   "rx_errors", "dropped_fifo_full", "dropped_stopped", "dropped_link_down",
                   "dropped_shutdown", "markers_sent", "markers_dropped")
"""Cumulative Status fields; on the wire modulo 2**width, unwrapped by the decoder."""


def unwrap(previous: int | None, raw: int, bits: int) -> int:
    """Full value of a counter sent modulo ``2**bits``, nearest to ``previous`` (if known)."""
    if previous is None:
        return raw
    mod = 1 << bits
    delta = (raw - previous) % mod
    if delta >= mod // 2:
        delta -= mod
    return previous + delta


class StatusTracker:
    """Unwraps status counters and keeps ``events_lost`` exact as of the last status.

    ``link_events`` is the encoder's count of events put on the wire before the status;
    ``decoded`` the decoder's count of events returned before it in stream order.
    """

    def __init__(self) -> None:
        self._last: dict[str, int] = {}
        self._base: tuple[int, int] | None = None

    def update(self, raw: Status, link_events: int, decoded: int, widths: dict[str, int],
               counters: LinkCounters) -> Status:
        """Unwrap ``raw`` (fields modulo ``2**widths[name]``) and update ``counters``."""
        values: dict[str, Any] = {}
        for name in STATUS_COUNTERS:
            values[name] = unwrap(self._last.get(name), getattr(raw, name), widths[name])
        link = unwrap(self._last.get("link_events"), link_events, widths["link_events"])
        self._last.update(values)
        self._last["link_events"] = link
        if self._base is None:
            self._base = (link, decoded)
            counters.events_before_join = max(0, link - decoded)
        counters.events_lost = (link - self._base[0]) - (decoded - self._base[1])
        counters.events_lost_reported = values["events_dropped"]
        return dataclasses.replace(raw, **values)
