"""CAN and CAN FD frame layout (SPEC.md §5): encoder and incremental decoder.

11-bit IDs ``class << 4 | board_id``; every board→host frame starts with a frame sequence
counter (4 bits classic, 8 bits FD); events are 12-bit words (9-bit address, 3-bit step
delta), 4 slots in every 8-byte classic frame and 40 in every 64-byte FD frame (version 3),
or, for skins of more than 338 channels, 24-bit words (20-bit address, 4-bit delta) in
WIDE_EVENTS frames, 2 slots per classic and 20 per FD frame (version 4); unused slots are
empty (all ones); stamped against SYNC frames. Every frame type has one fixed length, so a
DBC (:mod:`protocols.dbc`) describes each exactly. The compiled loops are in
:mod:`protocols.can_kernels`.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Iterable

import numpy as np

from protocols import can_kernels as k
from protocols.constants import (
    DEFAULT_STEP_US,
    DEFAULT_SYNC_US,
    KNOWN_VERSIONS,
    N_CHANNELS,
    WIDE_VERSION,
)
from protocols.counters import StatusTracker, unwrap
from protocols.errors import ProtocolError
from protocols.event_input import E_SIZE, check_step_us, event_steps, idle_sync_step
from protocols.events import make_events
from protocols.record_fields import check_uint, command_fields, command_record, enum_or_int
from protocols.records import (
    COMMAND_KEY_DTYPE,
    Ack,
    Answer,
    CanFrame,
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
from protocols.session_layout import CLASS_OF_KIND, Reassembly, chunks, payload_of
from protocols.status_layout import (
    CLASSIC_STATUS_MUX,
    CLASSIC_WIDTHS,
    STATUS_WORDS,
    WORD_WIDTHS,
    status_from_words,
    status_words,
)
from protocols.versions import check_versions, refuse_version, wire_version

log = logging.getLogger(__name__)

_MUX0 = struct.Struct("<B6sB")
_MUX_WORDS = struct.Struct("<BI3s")
_MARKER_CLASSIC = struct.Struct("<B5sH")
_STATUS_FD = struct.Struct(f"<BB6s{len(STATUS_WORDS)}I4x")
_MARKER_FD = struct.Struct("<BB6sI")
_ACK = struct.Struct("<BBBBH")
ACK_SEQ_MOD = 128
"""The ACK counter of byte 1 bits 7..1 of every ACK frame counts modulo 128 (SPEC.md §5.6)."""
_COMMAND = struct.Struct("<BBHI")

STATUS_FRAMES_CLASSIC = 8
"""A classic status is this many multiplexed frames (mux 0..7)."""

STATUS_LEN_FD = _STATUS_FD.size
"""Data length (bytes) of a CAN FD STATUS frame."""


def can_id(frame_class: int, board_id: int) -> int:
    """The 11-bit arbitration ID of ``frame_class`` (1..10) for board ``board_id`` (0..15)."""
    return (frame_class << 4) | board_id


def full_events_frame(board_id: int, fd: bool) -> CanFrame:
    """An EVENTS frame of board ``board_id`` as long as every one is (for its wire time)."""
    n = k.EVENTS_LEN_FD if fd else k.EVENTS_LEN_CLASSIC
    return CanFrame(can_id(k.CLS_EVENTS, _board(board_id)), bytes(n), bool(fd))


def _board(board_id: int) -> int:
    if not 0 <= int(board_id) <= 15:
        raise ProtocolError(f"CAN board id {board_id} is outside 0..15")
    return int(board_id)


def _flags(running: bool, version: int) -> int:
    return int(bool(running)) | (version << 4)


class CanEncoder:
    """Encoder of one board's CAN frames (classic 8-byte or, with ``fd``, CAN FD 64-byte).

    ``step_us`` is the event time step (µs); ``sync_us`` the longest time between SYNC
    frames while events flow (µs); ``n_channels`` the board's channel count, which selects
    the format (:attr:`version`): narrow up to 338 channels, wide above. Frames are filled
    (SPEC.md §5.2): the caller decides when to flush by what it hands to :meth:`events` /
    :meth:`events_upto`.
    """

    def __init__(self, board_id: int = 0, fd: bool = False, step_us: int = DEFAULT_STEP_US,
                 sync_us: int = DEFAULT_SYNC_US, n_channels: int = N_CHANNELS) -> None:
        self.board_id = _board(board_id)
        self.fd = bool(fd)
        self.step_us = check_step_us(step_us)
        max_off = k.FD_MAX_OFFSET if self.fd else k.CLASSIC_MAX_OFFSET
        if not step_us <= sync_us <= (max_off + 1) * step_us:
            raise ProtocolError(f"sync_us={sync_us} must lie in [{step_us}, "
                                f"{(max_off + 1) * step_us}] µs for this CAN layout")
        self.sync_us = sync_us
        self._seq_mod = k.FD_SEQ_MOD if self.fd else k.CLASSIC_SEQ_MOD
        self._st = np.zeros(E_SIZE, dtype=np.int64)
        self._st[k.E_EPOCH] = k.EPOCH_MOD - 1
        self._st[k.E_STEP_US] = self.step_us
        self.version = wire_version(n_channels)
        """Protocol version of this stream: 3 narrow, 4 wide (SPEC.md §9)."""
        self.n_channels = int(n_channels)
        self._st[k.E_VERSION] = self.version
        self._cmd_seq = 0
        self._ack_seq = 0
        self._t_min_us = 0
        self._ids = [can_id(c, self.board_id) for c in range(8)]
        self._sync_every = sync_us // step_us
        self._out = np.empty(0, dtype=np.uint8)
        self._lens = np.empty(0, dtype=np.int64)
        self._kinds = np.empty(0, dtype=np.int64)

    @property
    def events_encoded(self) -> int:
        """Events put into frames so far (the count status frames carry)."""
        return int(self._st[k.E_EVENTS])

    @property
    def frame_events(self) -> int:
        """Most events one events frame of this stream carries (4 or 40; wide 2 or 20)."""
        if self.version == WIDE_VERSION:
            return k.FD_MAX_WIDE if self.fd else k.CLASSIC_MAX_WIDE
        return k.FD_MAX_EVENTS if self.fd else k.CLASSIC_MAX_EVENTS

    def events(self, events: np.ndarray, t_end_us: int) -> list[CanFrame]:
        """SYNC and EVENTS frames carrying ``events`` (times in [end of last call, t_end_us)).

        An empty call returns a SYNC if the last one is ``sync_us`` old, else nothing.
        """
        return self.events_upto(events, t_end_us)[0]

    def events_upto(self, events: np.ndarray, t_end_us: int, max_frames: int | None = None
                    ) -> tuple[list[CanFrame], int]:
        """Like :meth:`events`, but at most ``max_frames`` events frames: returns the frames
        and how many of ``events`` (the first ones) they carry.

        A sender with more events than its link takes hands them all and sends whole
        frames only; the events left are handed again with the next call (this call then
        covers board time up to the first of them).
        """
        steps, addr = event_steps(events, self.step_us, t_end_us, self._t_min_us,
                                  self.n_channels)
        st, fd = self._st, self.fd
        if steps.shape[0] == 0:
            self._t_min_us = max(self._t_min_us, int(t_end_us))
            end_step = idle_sync_step(st, t_end_us, self.step_us, self.sync_us)
            if end_step is not None:
                out = np.zeros(16, dtype=np.uint8)
                n = k.encode_sync(st, end_step, fd, out, 0)
                return [CanFrame(self._ids[k.CLS_SYNC], out[:n].tobytes(), fd)], 0
            return [], 0
        n_ev = steps.shape[0]
        if self._out.shape[0] < 70 * n_ev + 80:
            self._out = np.empty(140 * n_ev + 80, dtype=np.uint8)
            self._lens = np.empty(4 * n_ev + 4, dtype=np.int64)
            self._kinds = np.empty(4 * n_ev + 4, dtype=np.int64)
        limit = n_ev if max_frames is None else max(1, int(max_frames))
        nf, used = k.encode_events(steps, addr, st, self._sync_every, fd, limit, self._out,
                                   self._lens, self._kinds)
        self._t_min_us = max(self._t_min_us, int(t_end_us) if used == n_ev
                             else int(steps[used]) * self.step_us)
        lens = self._lens[:nf].tolist()
        data = self._out[:sum(lens)].tobytes()
        ids = self._ids
        frames = []
        start = 0
        for ln, kind in zip(lens, self._kinds[:nf].tolist(), strict=True):
            frames.append(CanFrame(ids[kind], data[start:start + ln], fd))
            start += ln
        return frames, int(used)

    def _next_seq(self) -> int:
        seq = int(self._st[k.E_SEQ])
        self._st[k.E_SEQ] = (seq + 1) % self._seq_mod
        return seq

    def status(self, status: Status) -> list[CanFrame]:
        """STATUS frame(s): one 64-byte FD frame, or eight multiplexed 8-byte classic frames."""
        t = check_uint(status.t_us, 48, "status time (µs)").to_bytes(6, "little")
        ident = self._ids[k.CLS_STATUS]
        flags = _flags(status.running, self.version)
        if self.fd:
            words = status_words(status, self.events_encoded, WORD_WIDTHS)
            data = _STATUS_FD.pack(self._next_seq(), flags, t,
                                   *(words[name] for name in STATUS_WORDS))
            return [CanFrame(ident, data, True)]
        words = status_words(status, self.events_encoded, CLASSIC_WIDTHS)
        parts = [_MUX0.pack(0, t, flags)]
        for mux, (a, b) in enumerate(CLASSIC_STATUS_MUX, start=1):
            parts.append(_MUX_WORDS.pack(mux << 4, words[a],
                                         (0 if b is None else words[b]).to_bytes(3, "little")))
        return [CanFrame(ident, bytes([p[0] | self._next_seq()]) + p[1:], False)
                for p in parts]

    def marker(self, marker: Marker) -> list[CanFrame]:
        """A MARKER frame (ground truth: stimulus id and phase at board time)."""
        phase = check_uint(int(marker.phase), 1, "marker phase")
        ident = self._ids[k.CLS_MARKER]
        t_us = check_uint(marker.t_us, 48, "marker time (µs)")
        if self.fd:
            data = _MARKER_FD.pack(self._next_seq(), phase, t_us.to_bytes(6, "little"),
                                   check_uint(marker.stimulus_id, 32, "stimulus_id"))
            return [CanFrame(ident, data, True)]
        data = _MARKER_CLASSIC.pack(self._next_seq() | (phase << 4),
                                    (t_us & ((1 << 40) - 1)).to_bytes(5, "little"),
                                    check_uint(marker.stimulus_id, 16, "stimulus_id (classic)"))
        return [CanFrame(ident, data, False)]

    def command(self, command: Command | Decision | Answer) -> list[CanFrame]:
        """A COMMAND frame (host→board; commands have their own sequence counter)."""
        token, opcode, arg = command_fields(command)
        seq, self._cmd_seq = self._cmd_seq, (self._cmd_seq + 1) % self._seq_mod
        data = _COMMAND.pack(seq, opcode, token, arg)
        return [CanFrame(self._ids[k.CLS_COMMAND], data, self.fd)]

    def session_record(self, record: SessionRecord) -> list[CanFrame]:
        """The frames of a session record (SPEC.md §5.8): its payload in chunks, one per
        frame with consecutive sequence numbers (classic: chunk index in byte 0 bits 7..4)."""
        kind, payload = payload_of(record)
        ident = can_id(CLASS_OF_KIND[kind], self.board_id)
        frames = []
        for i, part in enumerate(chunks(payload, self.fd)):
            seq = self._next_seq()
            head = bytes([seq]) if self.fd else bytes([seq | i << 4])
            frames.append(CanFrame(ident, head + part, self.fd))
        return frames

    def ack(self, ack: Ack) -> list[CanFrame]:
        """An ACK frame (board→host answer to a command); byte 1 carries the ACK counter
        (bits 7..1, modulo 128) beside ok (bit 0), SPEC.md §5.6."""
        ack_seq, self._ack_seq = self._ack_seq, (self._ack_seq + 1) % ACK_SEQ_MOD
        data = _ACK.pack(self._next_seq(), int(bool(ack.ok)) | ack_seq << 1,
                         check_uint(int(ack.opcode), 8, "opcode"),
                         check_uint(int(ack.reason), 8, "reason"),
                         check_uint(ack.token, 16, "token"))
        return [CanFrame(self._ids[k.CLS_ACK], data, self.fd)]


class CanDecoder:
    """Incremental decoder of one board's frames: feed frames in any batches.

    Frames of other boards or unknown IDs are counted in ``counters.foreign_frames``; never
    raises on bad frames (SPEC.md §6). ``versions`` are the protocol versions it reads
    (default both): a stream that announces another known version raises ProtocolError.
    """

    def __init__(self, board_id: int = 0, fd: bool = False,
                 versions: tuple[int, ...] = KNOWN_VERSIONS) -> None:
        self.board_id = _board(board_id)
        self.versions = check_versions(versions)
        self.fd = bool(fd)
        self.counters = LinkCounters()
        self._st = np.zeros(k.D_SIZE, dtype=np.int64)
        self._c = np.zeros(k.C_SIZE, dtype=np.int64)
        self._status = StatusTracker()
        self._group: list[bytes] = []
        self._group_seq = -1
        self._session = Reassembly(k.FD_SEQ_MOD if self.fd else k.CLASSIC_SEQ_MOD)
        self._last_ack_seq = -1

    def feed(self, frames: Iterable[CanFrame], max_records: int | None = None) -> DecodeResult:
        """Decode a batch of received frames (in bus order); with ``max_records``, build at
        most that many records (the rest as :class:`DecodeResult` says)."""
        frames = list(frames)
        if not frames:
            return DecodeResult.empty()
        ids = np.fromiter((f.arbitration_id for f in frames), dtype=np.int64, count=len(frames))
        datas = [bytes(f.data) for f in frames]
        lens = np.fromiter(map(len, datas), dtype=np.int64, count=len(datas))
        blob = np.frombuffer(b"".join(datas) + b"\0" * 8, dtype=np.uint8)
        t, a, ne, rec_ix, nr = k.decode_frames(ids, lens, blob, self.board_id, self.fd,
                                              self._st, self._c)
        refuse_version(int(self._st[k.D_VERSIONS]), self.versions)
        events = make_events(t[:ne], a[:ne])
        records: list[Record] = []
        built = nr if max_records is None else min(nr, max(0, int(max_records)))
        for f, cls, decoded, ref_us in rec_ix[:built].tolist():
            record = self._record(cls, datas[f], decoded, ref_us)
            if record is not None:
                records.append(record)
        self._sync_counters()
        if built == nr:
            return DecodeResult(events, records)
        rest = rec_ix[built:nr]
        command = rest[:, 1] == k.CLS_COMMAND
        at = (np.cumsum(lens) - lens)[rest[command, 0]]  # each frame's first byte in blob
        keys = np.empty(at.shape[0], dtype=COMMAND_KEY_DTYPE)
        keys["token"] = blob[at + 2] | blob[at + 3].astype(np.uint16) << 8  # _COMMAND's layout
        keys["opcode"] = blob[at + 1]
        return DecodeResult(events, records, keys, int(command.shape[0] - at.shape[0]))

    def _record(self, cls: int, data: bytes, decoded: int, ref_us: int) -> Record | None:
        if cls == k.CLS_STATUS:
            return self._fd_status(data, decoded) if self.fd else self._classic_status(
                data, decoded)
        if cls == k.CLS_MARKER:
            if self.fd:
                _, phase, t, sid = _MARKER_FD.unpack(data[:12])
                return Marker(int.from_bytes(t, "little"), sid, MarkerPhase(phase))
            b0, t, sid = _MARKER_CLASSIC.unpack(data[:8])
            t_us = int.from_bytes(t, "little")
            if ref_us >= 0:
                t_us = unwrap(ref_us, t_us, 40)
            return Marker(t_us, sid, MarkerPhase(b0 >> 4))
        if cls == k.CLS_COMMAND:
            _, op, token, bits = _COMMAND.unpack(data[:8])
            return command_record(token, op, bits)
        if cls >= k.CLS_SESSION:
            kind = cls - k.CLS_SESSION
            if self.fd:
                return self._session.add(kind, data[1], data[0], data[2:64])
            return self._session.add(kind, data[0] >> 4, data[0] & 0xF, data[1:8])
        _, ok, op, reason, token = _ACK.unpack(data[:6])
        self._count_acks(ok >> 1)
        return Ack(token, enum_or_int(CommandCode, op), bool(ok & 1),
                   enum_or_int(NackReason, reason))

    def _count_acks(self, ack_seq: int) -> None:
        """Follow the ACK counter (SPEC.md §5.6): ACKs missing between two received ones go
        to ``counters.acks_lost``. A counter that does not move (a board that sends 0, as
        before the counter existed) counts nothing."""
        last, self._last_ack_seq = self._last_ack_seq, ack_seq
        if last >= 0 and ack_seq != last:
            self.counters.acks_lost += (ack_seq - last - 1) % ACK_SEQ_MOD

    def _fd_status(self, data: bytes, decoded: int) -> Status:
        _, flags, t, *v = _STATUS_FD.unpack(data[:STATUS_LEN_FD])
        raw, link = status_from_words(int.from_bytes(t, "little"), bool(flags & 1),
                                      dict(zip(STATUS_WORDS, v, strict=True)))
        return self._status.update(raw, link, decoded, WORD_WIDTHS, self.counters)

    def _classic_status(self, data: bytes, decoded: int) -> Status | None:
        seq, mux = data[0] & 0xF, data[0] >> 4
        if mux == 0:
            self._group = [data]
        elif mux == len(self._group) and seq == (self._group_seq + 1) % k.CLASSIC_SEQ_MOD:
            self._group.append(data)
        else:
            self._group = []
        self._group_seq = seq
        if len(self._group) < STATUS_FRAMES_CLASSIC:
            return None
        g, self._group = self._group, []
        _, t, flags = _MUX0.unpack(g[0][:8])
        words: dict[str, int] = {}
        for (a, b), d in zip(CLASSIC_STATUS_MUX, g[1:], strict=True):
            _, words[a], low = _MUX_WORDS.unpack(d[:8])
            if b is not None:
                words[b] = int.from_bytes(low, "little")
        raw, link = status_from_words(int.from_bytes(t, "little"), bool(flags & 1), words)
        return self._status.update(raw, link, decoded, CLASSIC_WIDTHS, self.counters)

    def _sync_counters(self) -> None:
        c, lc = self._c, self.counters
        lc.frames_ok = int(c[k.C_FRAMES_OK])
        lc.malformed = int(c[k.C_MALFORMED])
        lc.seq_gaps = int(c[k.C_GAPS])
        lc.frames_lost = int(c[k.C_LOST])
        lc.duplicates = int(c[k.C_DUPS])
        lc.foreign_frames = int(c[k.C_FOREIGN])
        lc.events_decoded = int(c[k.C_EVENTS])
        lc.events_untimed = int(c[k.C_UNTIMED])
        lc.syncs = int(c[k.C_SYNCS])
        lc.command_seq_gaps = int(c[k.C_CMD_GAPS])
        lc.commands_lost = int(c[k.C_CMD_LOST])

