"""The board's event accounting: every generated event is sent, dropped (by reason) or queued.

Invariant at any instant: ``generated = sent + dropped + queued`` with
``dropped = fifo_full + stopped + link_down + shutdown``. An event counts as *sent* when it
is encoded into the transmit queue (whose data always reaches the transport unless the link
goes away); *queued* is what waits in the event FIFO.

Drop reasons:

- ``fifo_full``: the FIFO had no room for a new event (tail drop, see
  :mod:`firmware_sim.fifo`), i.e. the spike rate exceeded the wire budget for too long;
- ``stopped``: the board was stopped (STOP command): the skin and neurons keep running, their
  events are not streamed;
- ``link_down``: the link was gone (waiting to reconnect), including events that were
  queued when it went away;
- ``shutdown``: still queued when the board stopped and the final drain timed out.

Ground-truth markers are counted apart: every marker that falls due is either sent
(``markers_sent``) or dropped (``markers_dropped``: the board was stopped, or the link was
gone), or still waits behind the events before its time. They are not events and never wait
behind dropped events: at shutdown the ones still due are sent after the FIFO is cleared.
Both counts are in every status on the wire.
"""

from __future__ import annotations

from dataclasses import dataclass, field

DROP_REASONS = ("fifo_full", "stopped", "link_down", "shutdown")


@dataclass
class BoardCounters:
    """Cumulative event counts since the board started."""

    generated: int = 0
    sent: int = 0
    dropped_by: dict[str, int] = field(default_factory=lambda: dict.fromkeys(DROP_REASONS, 0))
    rx_errors: int = 0
    """Host commands refused (SPEC.md §3.3): NACKed, failing the CRC or layout, repeating
    the host's previous sequence number, or not commands at all."""
    commands: int = 0
    nacks: int = 0
    busy: int = 0
    """Host commands refused as BUSY, beyond the tick's budget (also in ``nacks`` and
    ``rx_errors``; :mod:`firmware_sim.command_budget`)."""
    busy_by_opcode: dict[int, int] = field(default_factory=dict)
    """``busy`` by the refused commands' opcode (a GRIP refused BUSY never reached the held
    object: the grasp score counts it as ``refused_busy``)."""
    markers_sent: int = 0
    """Ground-truth markers encoded into the transmit queue."""
    markers_dropped: int = 0
    """Ground-truth markers never sent: the board was stopped or the link was gone when they
    fell due."""

    @property
    def dropped(self) -> int:
        return sum(self.dropped_by.values())

    def drop(self, reason: str, n: int) -> None:
        """Count ``n`` events dropped for ``reason`` (one of :data:`DROP_REASONS`)."""
        self.dropped_by[reason] += int(n)
