"""The receiving end of a closed grip loop: the board's stream decoded, its events and records
handed to listeners (the grip controller, the live view) as the reference receiver hands them
(:func:`skinhil.receiver.receiver.dispatch_record`), until the board's RUN_END.

It needs no stimulus decoder (the grasp task asks for none); it reads what
:func:`skinhil.receiver.session.run_against_board` reads of a receiver (``transport``,
``feed``, ``run_end``, ``flush``), so the same loop runs it against a board subprocess.
"""

from __future__ import annotations

import time
from typing import Any

import protocols
from skinhil.receiver.receiver import (
    LinkReport,
    ReceiverListener,
    dispatch_record,
    link_report,
    make_codec,
)
from skinhil.transports import Transport


class GripLoop:
    """Decodes ``transport``'s stream of board ``board_id`` for ``listeners``."""

    def __init__(self, transport: Transport[Any], listeners: list[ReceiverListener],
                 board_id: int = 0) -> None:
        self.transport = transport
        self.listeners = listeners
        self.codec = make_codec(transport, board_id)
        self.run_end: Any = None
        self.events = 0
        """Events decoded."""
        self.last_status: Any = None

    def feed(self, payload: Any, host_s: float | None = None) -> list[Any]:
        """Decode one payload (bytes or CAN frames) and hand on what it holds."""
        if not payload:
            return []
        h = time.monotonic() if host_s is None else host_s
        result = self.codec.feed(payload)
        if result.events.shape[0]:
            self.events += int(result.events.shape[0])
            for listener in self.listeners:
                listener.on_events(result.events, h)
        for rec in result.records:
            if isinstance(rec, protocols.Status):
                self.last_status = rec
            elif isinstance(rec, protocols.RunEnd):
                self.run_end = rec
            dispatch_record(rec, self.listeners)
        return []

    def link_report(self) -> LinkReport:
        """The link's counters and the board's last status (the live view shows them)."""
        return link_report(self.codec.counters, self.last_status)

    def flush(self) -> list[Any]:
        """Nothing is held back (the controller acts on each bin as it closes)."""
        return []
