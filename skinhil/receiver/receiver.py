"""The reference receiver: transport → protocols decoder → online classifier → listeners.

A :class:`Receiver` reads a :class:`skinhil.transports.Transport` (a pyserial port or a
python-can bus), feeds what arrives to the protocols decoder of that link (serial or CAN),
and passes the events to the :class:`~skinhil.receiver.online.OnlineClassifier` on board
time. Ground-truth markers go only to the :class:`~skinhil.receiver.scoring.Scoreboard`.
Listeners (python-can Notifier style) hear about events, decisions, markers, status
records, acknowledgements and link errors. Corrupted or lost data never stop it: the decoder
counts them, and a link that goes away is reported and, with ``reopen``, reopened.

The board's SESSION record configures what the stream says (its stimulus table names the
decisions; a decoder made for another channel count or step is reported) and its RUN_END
record ends :meth:`Receiver.run`: the board finished, not the link.

Board time is followed as the newest event's time (the stream is in time order), else the
newest marker time (or status time, when the board had no events queued) minus
``guard_s``; only while the stream has been silent for ``silence_s`` of host time (1 s,
ten of the board's status periods) does the host clock's estimate of board time from those
items (minus ``guard_s``) move it on, so items that arrive late because the board or the
link paused for a moment (a loaded host, user-mode Linux) are not taken as already
complete.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

import protocols
from skinhil.errors import SkinhilError, TransportError
from skinhil.model.stimuli import direction_conditions
from skinhil.receiver.announcement import Announcement
from skinhil.receiver.clock import BoardClock
from skinhil.receiver.decoder_adapter import WindowDecoder
from skinhil.receiver.online import OnlineClassifier
from skinhil.receiver.params import ReceiverParams
from skinhil.receiver.scoring import ScoredDecision, scoreboard_for
from skinhil.transports import Transport

log = logging.getLogger(__name__)


class ReceiverListener:
    """Override the callbacks you need; each is called on the receiving thread."""

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        """Events (EVENT_DTYPE) just decoded, received at host monotonic time (s)."""

    def on_decision(self, decision: ScoredDecision) -> None:
        """A decision of the online classifier, scored when a marker matches it."""

    def on_marker(self, marker: Any) -> None:
        """A ground-truth marker (``protocols.Marker``)."""

    def on_status(self, status: Any) -> None:
        """A board status record (``protocols.Status``)."""

    def on_ack(self, ack: Any) -> None:
        """A command acknowledgement (``protocols.Ack``)."""

    def on_session(self, session: Any) -> None:
        """The board's session record (``protocols.Session``): at its start, after a
        reconnect, on request."""

    def on_announcement(self, announcement: Announcement) -> None:
        """The board announced its suite case and the terms of each posed task (the SUITE and
        its TASK records are in, SPEC.md §3.7)."""

    def on_run_end(self, run_end: Any) -> None:
        """The board's run ended (``protocols.RunEnd``: when and why); no more data follows."""

    def on_link_error(self, message: str) -> None:
        """The link failed (message says how); the receiver goes on if it can."""


@dataclass(frozen=True)
class LinkReport:
    """Link and board loss figures at one moment (counts since the receiver started)."""

    events_decoded: int
    frames_ok: int
    crc_errors: int
    resyncs: int
    bytes_discarded: int
    seq_gaps: int
    frames_lost: int
    duplicates: int
    board_generated: int
    board_sent: int
    board_dropped: int
    lost_on_link: int
    """Events the board put on the wire that never came out of the decoder (the protocol's
    ``events_lost``: exact as of the last SYNC received)."""
    untimed_events: int
    """Events received in frames whose time base was lost (not returned; in lost_on_link)."""
    malformed: int
    late_events: int
    link_errors: int
    acks_lost: int = 0
    """CAN: the board's ACKs missing by their ACK counter (``protocols.LinkCounters``)."""
    sent_before_join: int = 0
    """Events the board had sent before the first STATUS the receiver got and it never
    decoded: a receiver that joined the run late (``protocols.LinkCounters.events_before_join``;
    not in ``lost_on_link``)."""

    def as_dict(self) -> dict[str, int]:
        return dict(self.__dict__)


def link_report(counters: Any, status: Any, late_events: int = 0,
                link_errors: int = 0) -> LinkReport:
    """The :class:`LinkReport` of a codec's ``counters`` and the board's last ``status``
    (None before any), with the receiver's own late events and link errors."""
    def g(obj: Any, name: str) -> int:
        return int(getattr(obj, name, 0) or 0)

    c, st = counters, status
    return LinkReport(
        events_decoded=g(c, "events_decoded"), frames_ok=g(c, "frames_ok"),
        crc_errors=g(c, "crc_errors"), resyncs=g(c, "resyncs"),
        bytes_discarded=g(c, "bytes_discarded"), seq_gaps=g(c, "seq_gaps"),
        frames_lost=g(c, "frames_lost"), duplicates=g(c, "duplicates"),
        board_generated=g(st, "events_generated"), board_sent=g(st, "events_sent"),
        board_dropped=g(st, "events_dropped"),
        lost_on_link=g(c, "events_lost"), untimed_events=g(c, "events_untimed"),
        malformed=g(c, "malformed"), late_events=late_events,
        link_errors=link_errors, acks_lost=g(c, "acks_lost"),
        sent_before_join=g(c, "events_before_join"))


LISTENER_CALLBACKS: dict[type, str] = {
    protocols.Marker: "on_marker", protocols.Status: "on_status", protocols.Ack: "on_ack",
    protocols.Session: "on_session", protocols.RunEnd: "on_run_end"}
"""The :class:`ReceiverListener` callback each kind of board record is handed to."""


def dispatch_record(record: Any, listeners: Iterable[ReceiverListener]) -> None:
    """Hand a decoded board ``record`` to each of ``listeners``' callback for its kind
    (:data:`LISTENER_CALLBACKS`; a kind without one, such as a STIMULUS entry, to none)."""
    name = LISTENER_CALLBACKS.get(type(record))
    if name is None:
        return
    for listener in listeners:
        getattr(listener, name)(record)


def make_codec(transport: Transport[Any], board_id: int = 0) -> Any:
    """The protocols decoder that fits ``transport``'s link."""
    return transport.codec_pair(board_id=board_id)[1]


def scored_classes(decoder: WindowDecoder) -> tuple[int, ...]:
    """Marker classes scored: the decoder's and always the 9 direction conditions (ids 0..8;
    a condition the decoder lacks can only be missed or wrong)."""
    n = len(direction_conditions())
    return tuple(sorted({int(c) for c in decoder.classes} | set(range(n))))


def _is_onset(marker: Any) -> bool:
    phase = getattr(marker, "phase", None)
    name = str(getattr(phase, "name", phase)).lower()
    return name.startswith("onset") or name == "0"


def in_stream_order(record: Any) -> bool:
    """Whether every event before the record's board time was sent before it: markers go in
    time order with the events; a status does only when the board had no events queued (a
    saturated board's status is stamped ahead of the events still waiting in its FIFO)."""
    return not (isinstance(record, protocols.Status) and record.events_queued > 0)


class Receiver:
    """Decode, filter and classify the stream of one board, listener style."""

    def __init__(self, transport: Transport[Any], decoder: WindowDecoder,
                 params: ReceiverParams | None = None, board_id: int = 0,
                 listeners: Iterable[ReceiverListener] = (),
                 reopen: Callable[[], Transport[Any]] | None = None) -> None:
        self.params = params or ReceiverParams()
        self.transport = transport
        self.board_id = board_id
        self.codec = make_codec(transport, board_id)
        self.classifier = OnlineClassifier(decoder, self.params.onset)
        self.scoreboard = scoreboard_for(scored_classes(decoder), self.classifier.windows,
                                         self.params.match_window_s)
        self.clock = BoardClock()
        self.listeners: list[ReceiverListener] = list(listeners)
        self.reopen = reopen
        self.last_status: Any = None
        self.link_errors = 0
        self._guard_us = int(round(self.params.guard_s * 1e6))
        self._last_event_us = -1
        self._last_record_us = -1
        self._last_item_host_s = -math.inf
        """Host time (s) of the newest board-stamped item in stream order."""
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.link_down = False
        self.session: Any = None
        """The board's last SESSION record (``protocols.Session``), or None."""
        self.stimuli: dict[int, str] = {}
        """The board's stimulus table (id → name) from the STIMULUS records after it."""
        self.announcement = Announcement()
        """The suite case the board plays and each posed task's terms (its SESSION, SUITE
        and TASK records)."""
        self.run_end: Any = None
        """The RUN_END record (``protocols.RunEnd``) once the board's run ended, else None."""
        self.run_ends = 0
        """RUN_END records received (a board restarted on the same link sends another)."""

    def add_listener(self, listener: ReceiverListener) -> None:
        self.listeners.append(listener)

    # -- processing ---------------------------------------------------------------------
    def feed(self, payload: Any, host_s: float | None = None) -> list[ScoredDecision]:
        """Process one received payload (bytes or CAN frames); return the new decisions."""
        h = time.monotonic() if host_s is None else host_s
        result = self.codec.feed(payload) if payload else None
        if result is not None:
            ev = result.events
            if ev.shape[0]:
                self.classifier.push(ev)
                self._last_event_us = max(self._last_event_us, int(ev["t"][-1]))
                self.clock.observe(int(ev["t"][-1]), h)
                self._last_item_host_s = h
                for listener in self.listeners:
                    listener.on_events(ev, h)
            for rec in result.records:
                self._record(rec, h)
        return self._advance(h)

    def _record(self, rec: Any, host_s: float) -> None:
        t = getattr(rec, "t_us", None)
        if t is not None and in_stream_order(rec):
            self._last_record_us = max(self._last_record_us, int(t))
            self.clock.observe(int(t), host_s)
            self._last_item_host_s = host_s
        if isinstance(rec, protocols.Marker):
            if _is_onset(rec):
                self.scoreboard.add_marker(int(rec.t_us), int(rec.stimulus_id))
        elif isinstance(rec, protocols.Status):
            self.last_status = rec
        elif isinstance(rec, protocols.Session):
            self._take_session(rec)
        elif isinstance(rec, protocols.StimulusEntry):
            self.stimuli[int(rec.stimulus_id)] = rec.name
        elif isinstance(rec, protocols.RunEnd):
            self.run_end = rec
            self.run_ends += 1
        if self.announcement.take(rec):
            for listener in self.listeners:
                listener.on_announcement(self.announcement)
        dispatch_record(rec, self.listeners)

    def _take_session(self, session: Any) -> None:
        """A SESSION: the stimulus table starts again; a decoder made for another stream
        is reported (the receiver goes on: its decisions are then meaningless)."""
        self.session = session
        self.stimuli = {}
        self.run_end = None
        decoder = self.classifier.decoder
        check = getattr(getattr(decoder, "decoder", None), "check_stream", None)
        if check is not None:
            try:
                check(int(session.n_channels), int(session.step_us) * 1e-6)
            except SkinhilError as exc:
                self._report(f"session: {exc}")

    def known_board_time_us(self, host_s: float | None = None) -> int:
        """Board time (µs) before which the stream is taken as complete."""
        guard = self._guard_us
        known = self._last_event_us
        if self._last_record_us >= 0:
            known = max(known, self._last_record_us - guard)
        h = time.monotonic() if host_s is None else host_s
        now = self.clock.board_now_us(h)
        if now is not None and h - self._last_item_host_s >= self.params.silence_s:
            known = max(known, now - guard)  # a silent stream still advances
        return known

    def _advance(self, host_s: float) -> list[ScoredDecision]:
        known = self.known_board_time_us(host_s)
        if known <= self.classifier.board_time_us:
            return []
        out = self._decide_until(known)
        late_us = self.classifier.windows.max_late_us
        if late_us and self._guard_us < late_us * 2:
            self._guard_us = min(int(round(self.params.max_guard_s * 1e6)), 2 * late_us)
            log.info("events arrived %.1f ms late: board-time guard now %.1f ms",
                     late_us * 1e-3, self._guard_us * 1e-3)
        return out

    def _decide_until(self, board_t_us: int) -> list[ScoredDecision]:
        """Filter and classify up to board time ``board_t_us`` (µs); score and announce the
        decisions, resolve the markers left behind."""
        out = []
        for pred in self.classifier.advance(board_t_us):
            scored = self.scoreboard.add_prediction(pred, self.clock.host_time_s)
            out.append(scored)
            for listener in self.listeners:
                listener.on_decision(scored)
        self.scoreboard.resolve(self.classifier.board_time_us)
        return out

    def flush(self) -> list[ScoredDecision]:
        """Process everything received up to the newest board time seen (end of a stream)."""
        return self._decide_until(max(self._last_event_us + 1, self._last_record_us))

    # -- the link -----------------------------------------------------------------------
    def poll(self, timeout: float | None = 0.02) -> list[ScoredDecision]:
        """Receive once (``timeout`` s, uniform semantics) and process; survive link errors."""
        if self.link_down:
            self._try_reopen()
            return self._advance(time.monotonic())
        try:
            payload = self.transport.recv(timeout)
        except TransportError as exc:
            self._link_error(str(exc))
            return []
        return self.feed(payload, time.monotonic())

    def drain(self) -> list[ScoredDecision]:
        """Decode everything the link already received (reads without waiting until one
        returns nothing): what a receiver does before it stops, so no frame it was handed is
        left undecoded and its totals are whole."""
        out: list[ScoredDecision] = []
        while not self.link_down:
            try:
                payload = self.transport.recv(0.0)
            except TransportError as exc:
                self._link_error(str(exc))
                break
            if not payload:
                break
            out += self.feed(payload, time.monotonic())
        return out

    def _report(self, message: str) -> None:
        log.warning("link error: %s", message)
        for listener in self.listeners:
            listener.on_link_error(message)

    def _link_error(self, message: str) -> None:
        self.link_errors += 1
        self.link_down = True
        self._report(message)
        if self.reopen is None:
            self._stop.set()

    def _try_reopen(self) -> None:
        if self.reopen is None:
            return
        time.sleep(0.2)
        try:
            self.transport = self.reopen()
        except TransportError as exc:
            log.debug("reopen failed: %s", exc)
            return
        self.link_down = False

    def run(self, duration_s: float | None = None, stop: threading.Event | None = None,
            until: Callable[[Receiver], bool] | None = None) -> None:
        """Poll until ``duration_s`` (s of wall time), ``stop`` is set, ``until(self)`` or
        the board's RUN_END record arrives."""
        end = None if duration_s is None else time.monotonic() + duration_s
        while not self._stop.is_set() and not (stop is not None and stop.is_set()):
            if self.run_end is not None:
                break
            if end is not None and time.monotonic() >= end:
                break
            if until is not None and until(self):
                break
            self.poll(0.02)

    def start(self) -> None:
        """Run :meth:`run` on a background thread until :meth:`stop`."""
        self._stop.clear()
        self._thread = threading.Thread(target=self.run, name="skinhil-receiver", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the background thread (if any); the transport stays open."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None

    # -- figures ------------------------------------------------------------------------
    def link_report(self) -> LinkReport:
        """Current link counters, board drops and events lost on the link."""
        return link_report(self.codec.counters, self.last_status,
                           self.classifier.late_events, self.link_errors)
