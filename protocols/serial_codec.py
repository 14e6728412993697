"""Serial packet stream (SPEC.md §2-§4): encoder and incremental decoder.

Packets are COBS-framed, zero-delimited, CRC-16 protected; events are 16-bit words (9-bit
address, 7-bit step delta) or a 338-bit bitmap for a crowded step (version 3), or 24-bit words
(20-bit address, 4-bit delta) for skins of more channels (version 4), stamped against an
explicit time base (SYNC). The compiled loops are in :mod:`protocols.serial_kernels`.
"""

from __future__ import annotations

import logging
import struct

import numpy as np

from protocols import serial_kernels as k
from protocols.constants import (
    BITMAP_BYTES,
    DEFAULT_STEP_US,
    DEFAULT_SYNC_US,
    KNOWN_VERSIONS,
    N_CHANNELS,
    WIDE_VERSION,
)
from protocols.counters import StatusTracker
from protocols.errors import ProtocolError
from protocols.event_input import E_SIZE, check_step_us, event_steps, idle_sync_step
from protocols.events import make_events
from protocols.framing import frame_into
from protocols.record_fields import check_uint, command_fields, command_record, enum_or_int
from protocols.records import (
    COMMAND_KEY_DTYPE,
    Ack,
    Answer,
    Command,
    CommandCode,
    Decision,
    DecodeResult,
    LinkCounters,
    Marker,
    MarkerPhase,
    NackReason,
    Record,
    SessionRecord,
    Status,
)
from protocols.session_layout import parse, payload_of
from protocols.status_layout import STATUS_WORDS, WORD_WIDTHS, status_from_words, status_words
from protocols.versions import check_versions, refuse_version, wire_version

log = logging.getLogger(__name__)

_STATUS = struct.Struct(f"<BB6s{len(STATUS_WORDS)}I")
_MARKER = struct.Struct("<BB6sIB")
_COMMAND = struct.Struct("<BBHBI")
_ACK = struct.Struct("<BBHBB")

MAX_PACKET_BYTES = k.MAX_WIRE + 1
"""Wire bytes of the longest packet (COBS-encoded, delimiter included)."""


def _u48(value: int) -> bytes:
    return check_uint(value, 48, "time (µs)").to_bytes(6, "little")


class SerialEncoder:
    """Encoder of one direction of the serial stream (board→host events and records, or
    host→board commands). Keeps the sequence number, SYNC epoch and event count.

    ``step_us`` is the event time step (µs); ``sync_us`` the longest time between SYNCs
    while events flow (µs); ``n_channels`` the board's channel count, which selects the
    format (:attr:`version`): narrow up to 338 channels, wide above. Packets are filled
    (SPEC.md §3.1): the caller decides when to flush by what it hands to :meth:`events` /
    :meth:`events_upto`.
    """

    def __init__(self, step_us: int = DEFAULT_STEP_US, sync_us: int = DEFAULT_SYNC_US,
                 n_channels: int = N_CHANNELS) -> None:
        self.step_us = check_step_us(step_us)
        if not step_us <= sync_us <= 0xFFFF * step_us:
            raise ProtocolError(f"sync_us={sync_us} must lie in [{step_us}, "
                                f"{0xFFFF * step_us}] µs")
        self.sync_us = sync_us
        self.version = wire_version(n_channels)
        """Protocol version of this stream: 3 narrow, 4 wide (SPEC.md §9)."""
        self.n_channels = int(n_channels)
        self._st = np.zeros(E_SIZE, dtype=np.int64)
        self._st[k.E_EPOCH] = k.EPOCH_MOD - 1
        self._st[k.E_STEP_US] = self.step_us
        self._st[k.E_VERSION] = self.version
        self._t_min_us = 0
        self._pkt = np.empty(k.MAX_BODY + 8, dtype=np.uint8)
        self._out = np.empty(2 * k.MAX_WIRE, dtype=np.uint8)

    @property
    def events_encoded(self) -> int:
        """Events put into packets so far (the count status packets carry)."""
        return int(self._st[k.E_EVENTS])

    @property
    def frame_events(self) -> int:
        """Most events one events packet carries (a body of bitmaps; wide: of 3-byte words)."""
        if self.version == WIDE_VERSION:
            return (k.MAX_BODY - 4) // k.WIDE_ITEM_BYTES
        return (k.MAX_BODY - 4) // (2 + BITMAP_BYTES) * N_CHANNELS

    def events(self, events: np.ndarray, t_end_us: int) -> bytes:
        """Packets carrying ``events`` (EVENT_DTYPE, times in [end of last call, t_end_us)).

        An empty call returns a SYNC if the last one is ``sync_us`` old, else nothing.
        """
        return self.events_upto(events, t_end_us)[0]

    def events_upto(self, events: np.ndarray, t_end_us: int,
                    max_packets: int | None = None) -> tuple[bytes, int]:
        """Like :meth:`events`, but at most ``max_packets`` events packets: returns the bytes
        and how many of ``events`` (the first ones) they carry.

        A sender with more events than its link takes hands them all and sends whole
        packets only; the events left are handed again with the next call (this call then
        covers board time up to the first of them).
        """
        steps, addr = event_steps(events, self.step_us, t_end_us, self._t_min_us,
                                  self.n_channels)
        st = self._st
        if steps.shape[0] == 0:
            self._t_min_us = max(self._t_min_us, int(t_end_us))
            end_step = idle_sync_step(st, t_end_us, self.step_us, self.sync_us)
            if end_step is not None:
                n = k.encode_sync(st, end_step, self._pkt, self._out, 0)
                return self._out[:n].tobytes(), 0
            return b"", 0
        n_ev = steps.shape[0]
        out = np.empty(32 * n_ev + 64, dtype=np.uint8)
        limit = n_ev if max_packets is None else max(1, int(max_packets))
        n, used = k.encode_events(steps, addr, st, self.sync_us // self.step_us, limit, out)
        self._t_min_us = max(self._t_min_us, int(t_end_us) if used == n_ev
                             else int(steps[used]) * self.step_us)
        return out[:n].tobytes(), int(used)

    def _packet(self, body: bytes) -> bytes:
        pkt = self._pkt
        pkt[:len(body)] = np.frombuffer(body, dtype=np.uint8)
        pkt[1] = self._st[k.E_SEQ]
        self._st[k.E_SEQ] = (self._st[k.E_SEQ] + 1) & 0xFF
        n = frame_into(pkt, len(body), self._out, 0)
        return self._out[:n].tobytes()

    def status(self, status: Status) -> bytes:
        """A STATUS packet; counters are sent modulo 2**32 with this encoder's event count."""
        words = status_words(status, self.events_encoded, WORD_WIDTHS)
        body = _STATUS.pack((k.T_STATUS << 5) | int(bool(status.running)), 0,
                            _u48(status.t_us), *(words[name] for name in STATUS_WORDS))
        return self._packet(body)

    def marker(self, marker: Marker) -> bytes:
        """A MARKER packet (ground truth: stimulus id and phase at board time)."""
        body = _MARKER.pack(k.T_MARKER << 5, 0, _u48(marker.t_us),
                            check_uint(marker.stimulus_id, 32, "stimulus_id"),
                            check_uint(int(marker.phase), 8, "marker phase"))
        return self._packet(body)

    def command(self, command: Command | Decision | Answer) -> bytes:
        """A COMMAND packet (host→board): a command or the decoder under test's decision."""
        token, opcode, arg = command_fields(command)
        body = _COMMAND.pack(k.T_COMMAND << 5, 0, token, opcode, arg)
        return self._packet(body)

    def session_record(self, record: SessionRecord) -> bytes:
        """A session-record packet (type 7, SPEC.md §3.7): the session, one row of the
        stimulus table, or the end of the run."""
        kind, payload = payload_of(record)
        return self._packet(bytes([(k.T_SESSION << 5) | kind, 0]) + payload)

    def ack(self, ack: Ack) -> bytes:
        """An ACK packet (board→host answer to a command)."""
        body = _ACK.pack((k.T_ACK << 5) | int(bool(ack.ok)), 0,
                         check_uint(ack.token, 16, "token"),
                         check_uint(int(ack.opcode), 8, "opcode"),
                         check_uint(int(ack.reason), 8, "reason"))
        return self._packet(body)


class SerialDecoder:
    """Incremental decoder of a serial packet stream: feed bytes in any chunking.

    Never raises on bad data: corrupted or foreign bytes are counted in :attr:`counters`
    and skipped (SPEC.md §6). ``versions`` are the protocol versions it reads (default both):
    a stream that announces another known version raises :class:`ProtocolError`.
    """

    def __init__(self, versions: tuple[int, ...] = KNOWN_VERSIONS) -> None:
        self.versions = check_versions(versions)
        self.counters = LinkCounters()
        self._pending = bytearray()
        self._st = np.zeros(k.D_SIZE, dtype=np.int64)
        self._c = np.zeros(k.C_SIZE, dtype=np.int64)
        self._status = StatusTracker()

    def feed(self, data: bytes, max_records: int | None = None) -> DecodeResult:
        """Decode every complete packet in the bytes received so far; with ``max_records``,
        build at most that many records (the rest as :class:`DecodeResult` says)."""
        pending = self._pending
        pending += data
        end = pending.rfind(0)
        if end < 0:
            if len(pending) > 2 * k.MAX_WIRE:
                cut = len(pending) - k.MAX_WIRE
                del pending[:cut]
                self._c[k.C_DISCARDED] += cut
                self._sync_counters()
            return DecodeResult.empty()
        buf = np.empty(end + 1, dtype=np.uint8)
        with memoryview(pending) as view:  # one copy, no lasting export of the bytearray
            buf[:] = np.frombuffer(view[:end + 1], dtype=np.uint8)
        del pending[:end + 1]
        t, a, ne, rec, rec_ix, nr = k.decode_stream(buf, self._st, self._c)
        refuse_version(int(self._st[k.D_VERSIONS]), self.versions)
        events = make_events(t[:ne], a[:ne])
        records: list[Record] = []
        built = nr if max_records is None else min(nr, max(0, int(max_records)))
        for off, m, decoded in rec_ix[:built].tolist():
            record = self._record(rec[off:off + m].tobytes(), decoded)
            if record is not None:
                records.append(record)
        self._sync_counters()
        if built == nr:
            return DecodeResult(events, records)
        off = rec_ix[built:nr, 0]
        command = rec[off] >> 5 == k.T_COMMAND
        at = off[command]
        keys = np.empty(at.shape[0], dtype=COMMAND_KEY_DTYPE)
        keys["token"] = rec[at + 2] | rec[at + 3].astype(np.uint16) << 8  # _COMMAND's layout
        keys["opcode"] = rec[at + 4]
        return DecodeResult(events, records, keys, int(command.shape[0] - at.shape[0]))

    def _record(self, body: bytes, decoded: int) -> Record | None:
        typ, low = body[0] >> 5, body[0] & 0x1F
        if typ == k.T_STATUS:
            _, _, t, *v = _STATUS.unpack(body)
            raw, link = status_from_words(int.from_bytes(t, "little"), bool(low & 1),
                                          dict(zip(STATUS_WORDS, v, strict=True)))
            return self._status.update(raw, link, decoded, WORD_WIDTHS, self.counters)
        if typ == k.T_MARKER:
            _, _, t, sid, phase = _MARKER.unpack(body)  # phase checked by the layout check
            return Marker(int.from_bytes(t, "little"), sid, MarkerPhase(phase))
        if typ == k.T_COMMAND:
            _, _, token, op, bits = _COMMAND.unpack(body)
            return command_record(token, op, bits)
        if typ == k.T_SESSION:  # fields checked by the layout check
            return parse(low, body[2:])
        _, _, token, op, reason = _ACK.unpack(body)
        return Ack(token, enum_or_int(CommandCode, op), bool(low & 1),
                   enum_or_int(NackReason, reason))

    def _sync_counters(self) -> None:
        c, lc = self._c, self.counters
        lc.frames_ok = int(c[k.C_FRAMES_OK])
        lc.crc_errors = int(c[k.C_CRC])
        lc.malformed = int(c[k.C_MALFORMED])
        lc.resyncs = int(c[k.C_RESYNCS])
        lc.bytes_discarded = int(c[k.C_DISCARDED])
        lc.seq_gaps = int(c[k.C_GAPS])
        lc.frames_lost = int(c[k.C_LOST])
        lc.duplicates = int(c[k.C_DUPS])
        lc.events_decoded = int(c[k.C_EVENTS])
        lc.events_untimed = int(c[k.C_UNTIMED])
        lc.syncs = int(c[k.C_SYNCS])
        lc.command_seq_gaps = int(c[k.C_CMD_GAPS])
        lc.commands_lost = int(c[k.C_CMD_LOST])
        lc.late_frames = int(c[k.C_LATE])



