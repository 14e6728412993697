"""Playing a recording onto a link (``serve --replay FILE``), at its recorded pace.

:class:`Replayer` sends each recorded unit at its host time's offset from the first
(divided by ``speed``): the bytes of each serial write as they were, the same datagrams on
UDP, frame for frame on CAN. It decodes what it plays with the protocol decoders (the
ground-truth markers reach :meth:`Replayer.on_marker`) and every host command it receives
goes to the one handler :meth:`Replayer.handle`, whose answer (a NACK, REPLAYING) is
inserted into the stream (:mod:`skinhil.recording.replay_stream`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

import protocols
from protocols.constants import DEFAULT_STEP_US
from protocols.resequence import can_frame_with_seq, serial_packet_with_seq
from protocols.warm_up import exercise_codecs
from skinhil.errors import ConfigError
from skinhil.lateness import LatenessLog
from skinhil.recording.recordings import Recording
from skinhil.recording.replay_stream import CanReplayStream, SerialReplayStream
from skinhil.scoring import DecisionScoreboard, answer_reason
from skinhil.transports import Transport

log = logging.getLogger(__name__)

SPIN_S = 2e-4
"""The last part (s) of each wait for a unit spent polling the clock, not asleep."""
POLL_S = 0.01
"""Longest sleep (s) between two looks for host commands while waiting."""
LATENESS_WINDOW = 100_000
"""Units whose lateness the percentiles are taken over (the most recent: bounded memory)."""
SWITCH_INTERVAL_S = 2e-4
"""Python's thread switch interval (s) while a replay runs (default 5 ms): a link's reader
thread (CAN) never holds the interpreter lock for longer than this against the next unit."""
SEND_TIMEOUT_S = 0.1
"""A send waits this long (s) at a time for a full link, then looks at the stop flag."""


_IDLE_STATUS = protocols.Status(t_us=0, events_generated=0, events_sent=0, events_dropped=0,
                                events_queued=0, late_ticks=0, rx_errors=0, running=True)


@dataclass(frozen=True)
class ReplaySummary:
    """What a replay did: units, time, pace error (ms, send start minus due time, over the
    last :data:`LATENESS_WINDOW` units; the max over all) and host commands."""

    units: int
    wire_units: int
    """Bytes (serial, UDP) or frames (CAN) sent, answers included."""
    recorded_s: float
    wall_s: float
    speed: float
    lateness_ms: dict[str, float]
    commands: int
    """Host commands received (each answered with a NACK, REPLAYING)."""
    rx_errors: int
    """Host units refused, counted as a board's STATUS counts them (SPEC.md §3.3
    ``rx_errors``): every command answered with a NACK (all but the DECISIONs scored), every
    packet or frame failing the CRC or the layout, repeating the host's sequence number, or
    good but no command (a host's SYNC or EVENTS)."""
    markers: int
    """Ground-truth markers played."""
    events: int
    """Events played (decoded from the replayed stream)."""
    complete: bool
    """Every unit of the recording was played (False: stopped early)."""

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


class Replayer:
    """Plays ``recording`` onto ``transport`` (a link of the kind it was recorded on).

    ``speed``: 1 plays at the recorded pace, 2 twice as fast, ``inf`` as fast as the link
    takes. Raises ConfigError when the link does not fit the recording.
    """

    def __init__(self, recording: Recording, transport: Transport[Any],
                 speed: float = 1.0, scoreboard: DecisionScoreboard | None = None) -> None:
        if not (speed > 0 and not math.isnan(speed)):
            raise ConfigError(f"--speed must be a positive number, got {speed!r}")
        if transport.kind != recording.link:
            raise ConfigError(f"'{recording.path}' was recorded on a {recording.link} link, "
                              f"this one is {transport.kind}: replay it onto a "
                              f"{recording.link} link")
        if recording.fd and not transport.can_fd:
            raise ConfigError(f"'{recording.path}' holds CAN FD frames: replay them onto a "
                              "CAN FD link (--fd, or fd=1 in --link)")
        self.recording = recording
        self.transport = transport
        self.scoreboard = scoreboard
        """Scores the DECISIONs received against the markers played (None: NACK them)."""
        self.speed = float(speed)
        self.frames = transport.carries_frames
        """True when the link carries frames (played together), False for bytes."""
        self._stream: Any = CanReplayStream() if self.frames else SerialReplayStream()
        self._answers, self._commands = self._codecs()
        self._played: Any = self._codecs()[1]
        self.commands = 0
        self.rx_errors = 0
        """Host units refused so far (:attr:`ReplaySummary.rx_errors`)."""
        self.markers = 0
        self.board_time_us = 0
        """The latest board time (µs) the played stream carried (events, statuses, markers):
        what a host command received now is stamped with."""
        self._late = LatenessLog(LATENESS_WINDOW)
        self._units = 0
        self._wire_units = 0

    # -- the one handler of host commands and of the markers played -------------------
    def handle(self, command: Any) -> Any:
        """Answer a host command received during the replay: a DECISION is stamped with the
        board time played so far and scored against the markers played (its ACK as the
        board's, SPEC §3.5.2); any other command gets a NACK, REPLAYING (no command is
        executed; the board that made the recording is not here)."""
        self.commands += 1
        if isinstance(command, protocols.Decision) and self.scoreboard is not None:
            outcome = self.scoreboard.decision(command.stimulus_id, self.board_time_us,
                                               command.confidence, True, command.token)
            reason = answer_reason(outcome)
            return protocols.Ack(token=command.token, opcode=command.opcode,
                                 ok=reason == protocols.NackReason.NONE, reason=reason)
        return protocols.Ack(token=command.token, opcode=command.opcode, ok=False,
                             reason=protocols.NackReason.REPLAYING)

    def on_marker(self, marker: Any) -> None:
        """A ground-truth marker was played (board time ``marker.t_us`` µs): an onset opens
        a response window on the scoreboard."""
        self.markers += 1
        if self.scoreboard is not None and marker.phase == protocols.MarkerPhase.ONSET:
            self.scoreboard.onset(marker.stimulus_id, marker.t_us)

    def warm_up(self) -> None:
        """Run every encode, decode and renumbering path once on throwaway codecs, off the
        clock (a kernel compiled inside the loop would stall the replay for up to a
        second)."""
        wide = protocols.N_CHANNELS + 1 if self.recording.wire_version == 4 else None
        payloads = exercise_codecs(*self._codecs(wide), DEFAULT_STEP_US, _IDLE_STATUS)
        if self.frames:
            can_frame_with_seq(payloads[0][0], 1)
        else:
            serial_packet_with_seq(payloads[0], 1)

    def _codecs(self, n_channels: int | None = None) -> tuple[Any, Any]:
        """A fresh (encoder, decoder) of the link's codecs in the recording's layout."""
        return self.transport.codec_pair(board_id=self.recording.board_id,
                                         n_channels=n_channels, fd=self.recording.fd)

    # -- the loop ------------------------------------------------------------------------
    def _poll_commands(self) -> None:
        data = self.transport.recv(timeout=0)
        if not data:
            return
        c = self._commands.counters
        before = c.frames_ok + c.crc_errors + c.malformed + c.duplicates
        commands = [r for r in self._commands.feed(data).records
                    if isinstance(r, protocols.Command | protocols.Decision | protocols.Answer)]
        # every unit but the commands is refused: bad, repeated, or good and no command
        units = c.frames_ok + c.crc_errors + c.malformed + c.duplicates - before
        self.rx_errors += units - len(commands)
        for record in commands:
            ack = self.handle(record)
            self.rx_errors += not ack.ok
            answer = self._answers.ack(ack)
            for unit in (answer if self.frames else [answer]):
                self._stream.answer(unit)

    def _wait(self, due: float, stop: threading.Event) -> None:
        while not stop.is_set():
            left = due - time.monotonic()
            if left <= SPIN_S:
                break
            self._poll_commands()
            time.sleep(min(left - SPIN_S, POLL_S))
        while time.monotonic() < due and not stop.is_set():
            pass

    def _send(self, payload: Any, stop: threading.Event) -> None:
        """Send all of ``payload`` (waiting for a full link), unless stopped."""
        while payload and not stop.is_set():
            n = self.transport.send(payload, timeout=SEND_TIMEOUT_S)
            self._wire_units += n
            payload = payload[n:]

    def _play(self, sends: list[Any], stop: threading.Event) -> None:
        """Send ``sends`` (a CAN stream's frames together; a byte stream's payloads one by
        one: each answer apart from the recorded datagrams) and decode what was played."""
        for payload in ([sends] if self.frames else sends):
            if not payload:
                continue
            self._send(payload, stop)
            res = self._played.feed(payload)
            if len(res.events):
                self.board_time_us = max(self.board_time_us, int(res.events["t"][-1]))
            for record in res.records:
                if isinstance(record, protocols.Status | protocols.Marker):
                    self.board_time_us = max(self.board_time_us, int(record.t_us))
                if isinstance(record, protocols.Marker):
                    self.on_marker(record)
            if self.scoreboard is not None:
                self.scoreboard.advance(self.board_time_us)

    def lateness_s(self) -> np.ndarray:
        """Each unit's send start minus its due time (s), in play order, for the last
        :data:`LATENESS_WINDOW` units."""
        return self._late.lateness_s()

    def run(self, stop: threading.Event | None = None) -> ReplaySummary:
        """Play the whole recording (or until ``stop`` is set); return what was done.
        Raises :class:`skinhil.errors.TransportError` when the link goes away."""
        stop = stop or threading.Event()
        self.warm_up()
        switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL_S)
        try:
            return self._run(stop)
        finally:
            sys.setswitchinterval(switch_interval)

    def _run(self, stop: threading.Event) -> ReplaySummary:
        wall0 = time.monotonic()
        first_ts: float | None = None
        last_ts = 0.0
        complete = True
        for ts, unit in self.recording.read():
            if stop.is_set():
                complete = False
                break
            first_ts = ts if first_ts is None else first_ts
            last_ts = ts
            due = wall0 + (ts - first_ts) / self.speed
            self._wait(due, stop)
            self._late.record(time.monotonic() - due)
            self._units += 1
            self._poll_commands()
            self._play(self._stream.out(unit), stop)
        self._poll_commands()
        self._play(self._stream.flush(), stop)
        pct = self._late.percentiles_ms()
        return ReplaySummary(
            units=self._units, wire_units=self._wire_units,
            recorded_s=(last_ts - first_ts) if first_ts is not None else 0.0,
            wall_s=time.monotonic() - wall0, speed=self.speed, lateness_ms=pct,
            commands=self.commands, rx_errors=self.rx_errors, markers=self.markers,
            events=int(self._played.counters.events_decoded), complete=complete and
            self._units == self.recording.units)
