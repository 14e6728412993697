"""The board's side of the link: encode records and events, pace them, read host commands.

One :class:`BoardLink` owns a transport, the protocol encoder and decoder that fit it
(the link's :meth:`~skinhil.transports.Transport.codec_pair`), and a small transmit queue
of encoded data; events are encoded in filled frames (:meth:`BoardLink.queue_events`).
:meth:`BoardLink.pump` hands the queue to the transport no faster than the wire allows
(:class:`firmware_sim.pacing.WirePacer`), without ever blocking: what the OS does not take
stays queued, like bytes in a UART's transmit buffer.
"""

from __future__ import annotations

import collections
import logging
import math
import time
from typing import Any

import numpy as np

import protocols
from firmware_sim.pacing import WirePacer
from protocols.records import COMMAND_KEY_DTYPE
from protocols.warm_up import exercise_codecs
from skinhil.transports import Transport

log = logging.getLogger(__name__)


class BoardLink:
    """Encoder + transmit queue + pacer + command decoder over one transport.

    ``allowance_s`` is the transmit buffer in seconds of wire time (see
    :class:`~firmware_sim.pacing.WirePacer`); ``board_id`` selects the CAN layout (the link
    says whether it is CAN FD); ``step_us`` is the timestamp resolution (µs); ``n_channels``
    the board's channel count (it selects the narrow or the wide format, SPEC.md §9). On a
    link of whole datagrams (UDP) every send holds whole packets only (SPEC.md §10).
    """

    def __init__(self, transport: Transport[Any], board_id: int = 0,
                 allowance_s: float = 1e-3, step_us: int = 100,
                 n_channels: int = protocols.N_CHANNELS) -> None:
        self.transport = transport
        self.frames = transport.carries_frames
        """True when the link carries frames (a frame queue), False for bytes."""
        self.whole_packets = transport.whole_datagrams
        self._codec_args: dict[str, Any] = {"board_id": board_id, "step_us": step_us,
                                            "n_channels": n_channels}
        self.encoder, self.decoder = transport.codec_pair(**self._codec_args)
        if self.frames:
            self._frames: collections.deque[Any] = collections.deque()
            self._frame_s: collections.deque[float] = collections.deque()
            self.frame_s = transport.wire_seconds(
                [protocols.full_events_frame(board_id, transport.can_fd)])
        else:
            self._bytes = bytearray()
            self._byte_s = transport.wire_seconds(b"x")
            self.frame_s = protocols.MAX_PACKET_BYTES * self._byte_s
        """Wire time (s) of a full events frame (packet)."""
        self.frame_events: int = self.encoder.frame_events
        """Most events one events frame (packet) carries."""
        self.pacer = WirePacer(allowance_s)
        self._backlog_s = 0.0
        self.units_sent = 0
        """Bytes (serial) or frames (CAN) handed to the transport."""
        self.rx_errors = 0
        """Host units refused so far (SPEC.md §3.3, ``rx_errors``): packets or frames that fail
        the CRC or the layout (``crc_errors`` + ``malformed``), repeated host sequence numbers
        (``duplicates``: dropped unanswered), good packets or frames that are not commands (a
        host's SYNC or EVENTS), and data the decoder rejected by raising (a correct decoder
        never does). NACKs are the board's."""
        self._rx_reported = 0
        self._rx_taken = 0
        self._rx_units = 0
        sample = transport.codec_pair(**self._codec_args)[0].ack(
            protocols.Ack(token=0xFFFF, opcode=0xFF, ok=False, reason=0xFF))
        self.answer_wire_s: float = (transport.wire_seconds(sample) if self.frames
                                     else len(sample) * self._byte_s)
        """Wire time (s) of one ACK on this link (:mod:`firmware_sim.command_budget`)."""

    def warm_up(self, status: Any) -> None:
        """Run every encode and decode path once on throwaway codecs, off the clock
        (:func:`exercise_codecs`); the link's own encoder, decoder and queue are untouched."""
        encoder, decoder = self.transport.codec_pair(**self._codec_args)
        for payload in exercise_codecs(encoder, decoder, self._codec_args["step_us"], status):
            if self.frames:
                for frame in payload:
                    self.transport.wire_seconds([frame])

    # -- transmit queue ---------------------------------------------------------------
    def _queue(self, payload: Any) -> None:
        if self.frames:
            for frame in payload:
                s = self.transport.wire_seconds([frame])
                self._frames.append(frame)
                self._frame_s.append(s)
                self._backlog_s += s
        elif payload:
            self._bytes += payload
            self._backlog_s += len(payload) * self._byte_s

    def backlog_s(self) -> float:
        """Wire time (s) of the encoded data still queued."""
        return max(0.0, self._backlog_s)

    def queued_units(self) -> int:
        """Bytes or frames still queued."""
        return len(self._frames) if self.frames else len(self._bytes)

    def queue_events(self, events: np.ndarray, t_end_us: int,
                     max_frames: int | None = None) -> int:
        """Encode ``events`` (all with ``t < t_end_us``) in filled frames and queue them.

        With ``max_frames``, at most that many EVENTS frames (packets): returns how many of
        ``events`` (the first ones) they carry; the rest are for a later call.
        """
        payload, used = self.encoder.events_upto(events, t_end_us, max_frames)
        self._queue(payload)
        return int(used)

    def queue_record(self, record: Any) -> None:
        """Encode and queue a Status, Marker, Ack or session record (Session,
        StimulusEntry, SuiteEntry, TaskEntry, RunEnd)."""
        if isinstance(record, protocols.Status):
            self._queue(self.encoder.status(record))
        elif isinstance(record, protocols.Marker):
            self._queue(self.encoder.marker(record))
        elif isinstance(record, protocols.Ack):
            self._queue(self.encoder.ack(record))
        elif isinstance(record, (protocols.Session, protocols.StimulusEntry,
                                 protocols.SuiteEntry, protocols.TaskEntry, protocols.RunEnd)):
            self._queue(self.encoder.session_record(record))
        else:
            raise TypeError(f"cannot send a {type(record).__name__}")

    def pump(self, now: float | None = None) -> int:
        """Hand queued data to the transport within the wire budget; never blocks.

        A byte or frame may start while the emulated wire is free within the pacer's
        allowance, however long it lasts.

        Returns the bytes or frames sent. Raises :class:`skinhil.errors.TransportError` if
        the link has gone away.
        """
        now = time.monotonic() if now is None else now
        room = self.pacer.room_s(now)
        if room <= 0:
            return 0
        if self.frames:
            batch, wire = [], 0.0
            while self._frames and wire < room - 1e-12:  # starts within the allowance
                wire += self._frame_s[0]
                batch.append(self._frames.popleft())
                self._frame_s.popleft()
            if not batch:
                return 0
            n = self.transport.send(batch, timeout=0)
            for frame in reversed(batch[n:]):  # not taken by the OS: keep them first
                self._frames.appendleft(frame)
                self._frame_s.appendleft(self.transport.wire_seconds([frame]))
            used = sum(self.transport.wire_seconds([f]) for f in batch[:n]) if n < len(batch) \
                else wire
        else:
            n_bytes = math.ceil(room / self._byte_s - 1e-9)  # bytes starting within it
            if n_bytes <= 0 or not self._bytes:
                return 0
            chunk = bytes(self._bytes[:n_bytes])
            if self.whole_packets:
                chunk = self._whole_packets(chunk, now)
                if not chunk:
                    return 0
            n = self.transport.send(chunk, timeout=0)
            del self._bytes[:n]
            used = n * self._byte_s
        self.pacer.used(used, now)
        self._backlog_s -= used
        self.units_sent += n
        return n

    def _whole_packets(self, chunk: bytes, now: float) -> bytes:
        """``chunk`` cut after its last packet delimiter; if it holds no whole packet, the
        first queued packet once the wire is idle (a packet longer than the allowance)."""
        cut = chunk.rfind(0) + 1
        if cut:
            return chunk[:cut]
        if self.pacer.free_at > now:
            return b""
        return bytes(self._bytes[:self._bytes.find(0) + 1])

    def drain(self, timeout_s: float) -> bool:
        """Pump until the queue is empty (True) or ``timeout_s`` (s) passed (False)."""
        end = time.monotonic() + timeout_s
        while self.queued_units():
            if time.monotonic() > end:
                return False
            self.pump()
            time.sleep(0.0005)
        return True

    def wait_wire_idle(self, timeout_s: float) -> None:
        """Sleep until the emulated wire has sent everything (at most ``timeout_s`` s)."""
        left = min(timeout_s, self.pacer.idle_at() - time.monotonic())
        if left > 0:
            time.sleep(left)

    # -- receive ------------------------------------------------------------------------
    def poll_commands(self, max_commands: int | None = None) -> tuple[list[Any], np.ndarray]:
        """Host commands and decisions (:class:`protocols.Command`, :class:`protocols.Decision`)
        received since the last call (never blocks), at most ``max_commands`` of them as
        records; the commands past them as token and opcode only
        (:data:`protocols.records.COMMAND_KEY_DTYPE`, see :class:`protocols.DecodeResult`)."""
        none = np.empty(0, dtype=COMMAND_KEY_DTYPE)
        data = self.transport.recv(timeout=0)
        if not data:
            return [], none
        try:
            res = self.decoder.feed(data, max_commands)
        except (ValueError, TypeError, KeyError) as exc:  # a decoder must not raise; be safe
            log.warning("undecodable host data dropped: %s", exc)
            self.rx_errors += 1
            return [], none
        c = self.decoder.counters
        refused = c.crc_errors + c.malformed + c.duplicates
        self.rx_errors += refused - self._rx_reported
        self._rx_reported = refused
        commands = [r for r in res.records
                    if isinstance(r, (protocols.Command, protocols.Decision,
                                      protocols.Answer))]
        # every good unit that is no command (a host's SYNC, EVENTS, STATUS, ...) is refused
        n_commands = len(commands) + res.excess_commands.shape[0]
        self.rx_errors += max(0, c.frames_ok - self._rx_units - n_commands)
        self._rx_units = c.frames_ok
        return commands, res.excess_commands

    def take_rx_errors(self) -> int:
        """Host units refused since the last call (see :attr:`rx_errors`)."""
        n = self.rx_errors - self._rx_taken
        self._rx_taken = self.rx_errors
        return n

    def shutdown(self) -> None:
        self.transport.shutdown()

