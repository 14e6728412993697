"""Several boards on one link: one :class:`Receiver` per board, and a combined view.

On a CAN bus every board has its board id (the low 4 bits of its frames' IDs, SPEC.md §5.1);
on a UDP port every board is a source address (SPEC.md §10). A :class:`BusReceiver` reads the
link, gives each board's :class:`Receiver` its own frames or datagrams (its own decoder,
counters, online classifier and scoreboard), and sums the boards' link reports. CAN frames of
no listed board are counted in :attr:`BusReceiver.foreign_frames`; a new UDP source becomes a
new board.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any

from protocols.constants import MAX_CAN_CLASS
from skinhil.errors import ConfigError, TransportError
from skinhil.receiver.decoder_adapter import WindowDecoder
from skinhil.receiver.params import ReceiverParams
from skinhil.receiver.receiver import LinkReport, Receiver, ReceiverListener
from skinhil.receiver.scoring import ScoredDecision
from skinhil.transports import Transport

log = logging.getLogger(__name__)

BoardKey = int | str
"""A board on the link: its CAN board id (int) or its UDP source ``"host:port"`` (str)."""

MAX_UDP_SOURCES = 16
"""Most UDP sources (boards) a bus receiver decodes by default; datagrams of further sources
are refused and counted (SPEC.md §10)."""


def combine(reports: Iterable[LinkReport]) -> LinkReport:
    """Field-by-field sum of several boards' link reports (the combined view)."""
    names = [f.name for f in dataclasses.fields(LinkReport)]
    total = dict.fromkeys(names, 0)
    for r in reports:
        for n in names:
            total[n] += getattr(r, n)
    return LinkReport(**total)


class BusReceiver:
    """Decode, filter and classify every board on one CAN bus or UDP port.

    ``board_ids`` (CAN: required) are the boards to decode; on UDP every source that sends is
    a board, up to ``max_sources`` of them (datagrams of further sources are refused and
    counted in :attr:`refused_datagrams`, so stray or hostile senders cannot grow the
    receiver without bound), and only sources in ``allow`` when it is given (each entry
    ``"host"`` or ``"host:port"``). ``listeners(key, receiver)`` gives the listeners of a new
    board's receiver.
    """

    def __init__(self, transport: Transport[Any], decoder: WindowDecoder,
                 board_ids: Iterable[int] = (), params: ReceiverParams | None = None,
                 listeners: Callable[[BoardKey, Receiver], Iterable[ReceiverListener]]
                 | None = None, max_sources: int = MAX_UDP_SOURCES,
                 allow: Iterable[str] | None = None) -> None:
        if not (transport.carries_frames or transport.whole_datagrams):
            raise ConfigError(f"a {transport.kind} link carries one board: use Receiver, or "
                              "several boards on a CAN bus or a UDP port")
        ids = sorted({int(b) for b in board_ids})
        if transport.carries_frames and not ids:
            raise ConfigError("give the board ids to decode on the CAN bus, e.g. 0, 5, 9")
        self.transport = transport
        self.decoder = decoder
        self.params = params or ReceiverParams()
        self._listeners = listeners or (lambda key, rx: ())
        self.boards: dict[BoardKey, Receiver] = {}
        """Each board's receiver, by board id (CAN) or source address (UDP)."""
        self.foreign_frames = 0
        """CAN frames of no listed board (or with an ID no board uses)."""
        if max_sources < 1:
            raise ConfigError(f"max_sources={max_sources}: allow at least one UDP source")
        self.max_sources = int(max_sources)
        self.allow = frozenset(allow) if allow is not None else None
        self.refused_datagrams = 0
        """UDP datagrams refused: their source is not allowed, or is new past
        ``max_sources``."""
        self.link_errors = 0
        self.link_down = False
        for b in ids:
            self._board(b)

    def _board(self, key: BoardKey) -> Receiver:
        rx = self.boards.get(key)
        if rx is None:
            board_id = key if isinstance(key, int) else 0
            rx = Receiver(self.transport, self.decoder, self.params, board_id=board_id)
            for listener in self._listeners(key, rx):
                rx.add_listener(listener)
            self.boards[key] = rx
            log.info("decoding board %s", key)
        return rx

    # -- processing ---------------------------------------------------------------------
    def split_frames(self, frames: list[Any]) -> dict[BoardKey, list[Any]]:
        """CAN frames grouped by board id (bus order kept); others counted as foreign."""
        out: dict[BoardKey, list[Any]] = {}
        for f in frames:
            ident = int(f.arbitration_id)
            board = ident & 0xF
            if ident > 0x7FF or not 1 <= ident >> 4 <= MAX_CAN_CLASS or board not in self.boards:
                self.foreign_frames += 1
                continue
            out.setdefault(board, []).append(f)
        return out

    def split_datagrams(self, grams: list[tuple[str, bytes]]) -> dict[BoardKey, bytes]:
        """UDP datagrams grouped by source (arrival order kept within each source); those of
        refused sources (not allowed, or new past ``max_sources``) counted and dropped."""
        out: dict[BoardKey, bytearray] = {}
        room = self.max_sources - len(self.boards)
        for src, data in grams:
            if src not in out:
                allowed = self.allow is None or src in self.allow \
                    or src.rsplit(":", 1)[0] in self.allow
                known = src in self.boards
                if not allowed or (not known and room <= 0):
                    self.refused_datagrams += 1
                    continue
                room -= 0 if known else 1
            out.setdefault(src, bytearray()).extend(data)
        return {k: bytes(v) for k, v in out.items()}

    def feed(self, parts: dict[BoardKey, Any],
             host_s: float | None = None) -> list[tuple[BoardKey, ScoredDecision]]:
        """Process each board's share of one reception (boards without data advance on the
        host clock); return the new decisions with their board."""
        h = time.monotonic() if host_s is None else host_s
        out: list[tuple[BoardKey, ScoredDecision]] = []
        for key in parts:
            self._board(key)
        for key, rx in self.boards.items():
            payload = parts.get(key, rx.transport.empty())
            out += [(key, d) for d in rx.feed(payload, h)]
        return out

    def receive(self, timeout: float | None) -> dict[BoardKey, Any]:
        """One reception from the link (``timeout`` s, uniform semantics), split by board."""
        if self.transport.carries_frames:
            return self.split_frames(self.transport.recv(timeout))
        return self.split_datagrams(self.transport.recv_from(timeout))  # type: ignore[attr-defined]

    def drain(self) -> list[tuple[BoardKey, ScoredDecision]]:
        """Decode everything the link already received (see :meth:`Receiver.drain`)."""
        out: list[tuple[BoardKey, ScoredDecision]] = []
        while not self.link_down:
            try:
                parts = self.receive(0.0)
            except TransportError as exc:
                self._link_error(exc)
                break
            if not parts:
                break
            out += self.feed(parts, time.monotonic())
        return out

    def poll(self, timeout: float | None = 0.02) -> list[tuple[BoardKey, ScoredDecision]]:
        """Receive once and process; a link error is reported to every board's listeners
        and stops :meth:`run`."""
        if self.link_down:
            return []
        try:
            parts = self.receive(timeout)
        except TransportError as exc:
            self._link_error(exc)
            return []
        return self.feed(parts, time.monotonic())

    def _link_error(self, exc: TransportError) -> None:
        self.link_errors += 1
        self.link_down = True
        log.warning("link error: %s", exc)
        for rx in self.boards.values():
            for listener in rx.listeners:
                listener.on_link_error(str(exc))

    def run(self, duration_s: float | None = None,
            stop: threading.Event | None = None) -> None:
        """Poll until ``duration_s`` (s of wall time), ``stop`` is set or the link fails."""
        end = None if duration_s is None else time.monotonic() + duration_s
        while not self.link_down and not (stop is not None and stop.is_set()):
            if end is not None and time.monotonic() >= end:
                break
            self.poll(0.02)

    def flush(self) -> list[tuple[BoardKey, ScoredDecision]]:
        """Process everything received up to each board's newest board time."""
        return [(key, d) for key, rx in self.boards.items() for d in rx.flush()]

    # -- figures ------------------------------------------------------------------------
    def link_reports(self) -> dict[BoardKey, LinkReport]:
        """Each board's link counters and losses."""
        return {key: rx.link_report() for key, rx in self.boards.items()}

    def combined_report(self) -> LinkReport:
        """The boards' link reports summed, with the bus's own link errors."""
        total = combine(self.link_reports().values())
        return dataclasses.replace(total, link_errors=total.link_errors + self.link_errors)
