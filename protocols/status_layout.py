"""Where each status counter sits on the wire (SPEC.md §3.3, §5.5): one table per layout.

A serial STATUS packet and a CAN FD STATUS frame carry the counters of :data:`STATUS_WORDS`
as u32 after the board time; a classic CAN status is seven multiplexed frames after the time
frame, each a u32 and a u24 (:data:`CLASSIC_STATUS_MUX`). ``link_events`` is the encoder's
own count of events put in EVENTS frames, not a field of :class:`~protocols.records.Status`.
"""

from __future__ import annotations

from typing import Any

from protocols.errors import ProtocolError
from protocols.records import Status

LINK_EVENTS = "link_events"

STATUS_WORDS = ("events_generated", "events_sent", "events_dropped", "events_queued",
                "late_ticks", "rx_errors", "dropped_fifo_full", "dropped_stopped",
                "dropped_link_down", LINK_EVENTS, "dropped_shutdown", "markers_sent",
                "markers_dropped")
"""The u32 counters of a serial or CAN FD status, in wire order after the time."""

CLASSIC_STATUS_MUX: tuple[tuple[str, str | None], ...] = (
    ("events_generated", "events_queued"), ("events_sent", "late_ticks"),
    ("events_dropped", "rx_errors"), ("dropped_fifo_full", "dropped_shutdown"),
    ("dropped_stopped", "markers_sent"), ("dropped_link_down", "markers_dropped"),
    (LINK_EVENTS, None))
"""Classic CAN status frames mux 1..7: (u32 at bytes 1..4, u24 at bytes 5..7 or None:
reserved, sent as 0)."""

WORD_WIDTHS = dict.fromkeys(STATUS_WORDS, 32)
"""Bits each counter has on a serial or CAN FD link (counters wrap modulo 2**bits)."""
CLASSIC_WIDTHS = ({a: 32 for a, _ in CLASSIC_STATUS_MUX}
                  | {b: 24 for _, b in CLASSIC_STATUS_MUX if b is not None})
"""Bits each counter has on a classic CAN link."""


def status_words(status: Status, link_events: int, widths: dict[str, int]) -> dict[str, int]:
    """The wire values of ``status`` (and ``link_events``), each modulo ``2**widths[name]``.

    Raises :class:`ProtocolError` for a negative counter, or an ``events_queued`` (a level,
    never unwrapped) that does not fit its field.
    """
    values: dict[str, int] = {}
    for name, bits in widths.items():
        v = int(link_events if name == LINK_EVENTS else getattr(status, name))
        if v < 0:
            raise ProtocolError(f"status {name} = {v} is negative; counters count up from 0")
        if name == "events_queued" and v >> bits:
            raise ProtocolError(f"events_queued = {v} does not fit the {bits}-bit field of "
                                "this layout; use a smaller FIFO")
        values[name] = v & ((1 << bits) - 1)
    return values


def status_from_words(t_us: int, running: bool, words: dict[str, Any]) -> tuple[Status, int]:
    """The raw (still wrapped) :class:`Status` and ``link_events`` of decoded wire values."""
    fields = {k: int(v) for k, v in words.items() if k != LINK_EVENTS}
    return Status(t_us=t_us, running=running, **fields), int(words[LINK_EVENTS])
