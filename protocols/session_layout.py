"""The payloads of the session records (SPEC.md §3.7): SESSION, STIMULUS and RUN_END.

Each record is one payload ``P`` of bytes, the same on every link: a serial packet of type 7
carries ``P`` after its two header bytes (its kind in byte 0 bits 4..0); on CAN (classes 8,
9, 10) ``P`` is cut into chunks, 7 bytes per classic frame and 62 per CAN FD frame
(:func:`chunks`), reassembled by :class:`Reassembly`. The stimulus table's digest is the
CRC-32 (ISO-HDLC, as zlib's) of the STIMULUS payloads in ascending id order.
"""

from __future__ import annotations

import math
import struct
import zlib
from collections.abc import Iterable

from protocols.constants import KNOWN_VERSIONS
from protocols.errors import ProtocolError
from protocols.record_fields import check_uint, enum_or_int
from protocols.records import (
    RunEnd,
    RunEndReason,
    Session,
    SessionReason,
    StimulusEntry,
)

KIND_SESSION, KIND_STIMULUS, KIND_RUN_END = 0, 1, 2
"""Serial type-7 kinds (byte 0 bits 4..0); kinds 3..31 are reserved for future records."""

CLASS_OF_KIND = {KIND_SESSION: 8, KIND_STIMULUS: 9, KIND_RUN_END: 10}
"""CAN frame class of each kind (ID = class << 4 | board id); classes 11..15 are reserved."""

SESSION_FIELDS: tuple[tuple[str, int, int], ...] = (
    ("TimeUs", 0, 6), ("Version", 6, 1), ("NChannels", 7, 4), ("StepUs", 11, 2),
    ("BoardId", 13, 1), ("TickUs", 14, 4), ("NStimuli", 18, 2), ("Reason", 20, 1),
    ("SnrDb", 21, 4), ("Rows", 25, 1), ("Cols", 26, 1), ("Flags", 27, 1),
    ("ResponseWindowUs", 28, 4), ("Tasks", 32, 2), ("TableDigest", 35, 4))
"""(DBC signal name, payload offset, bytes) of every SESSION field (byte 34 reserved); the
layout :data:`_SESSION` packs."""
RUN_END_FIELDS: tuple[tuple[str, int, int], ...] = (("TimeUs", 0, 6), ("Reason", 6, 1))
"""(DBC signal name, payload offset, bytes) of the RUN_END fields."""
_SESSION = struct.Struct("<6sBIHBIHBfBBBIHBI")
SESSION_BYTES = _SESSION.size
"""Length of a SESSION payload (39 bytes; no field straddles a 7-byte classic CAN chunk)."""
_RUN_END = struct.Struct("<6sB")
RUN_END_BYTES = _RUN_END.size
"""Length of a RUN_END payload (7 bytes)."""
STIMULUS_HEAD = 5
"""A STIMULUS payload: stimulus id (u32), name length n (u8), then n name bytes."""
MAX_NAME_BYTES = 64
"""Longest stimulus name on the wire (UTF-8 bytes)."""
CLASSIC_CHUNK, FD_CHUNK = 7, 62
"""Payload bytes per classic frame (after byte 0) and per CAN FD frame (after bytes 0, 1)."""
FD_FRAME_BYTES = 64
"""Every CAN FD session-record frame is 64 bytes long."""


def session_payload(s: Session) -> bytes:
    """The 39-byte SESSION payload of ``s``."""
    if int(s.version) not in KNOWN_VERSIONS:
        raise ProtocolError(f"session version {s.version}: choose among {KNOWN_VERSIONS}")
    if math.isnan(float(s.snr_db)):
        raise ProtocolError("session SNR is NaN; give a level in dB or inf")
    return _SESSION.pack(
        check_uint(s.t_us, 48, "session time (µs)").to_bytes(6, "little"), int(s.version),
        check_uint(s.n_channels, 32, "channel count"), check_uint(s.step_us, 16, "step_us"),
        check_uint(s.board_id, 8, "board id"), check_uint(s.tick_us, 32, "tick_us"),
        check_uint(s.n_stimuli, 16, "stimulus count"),
        check_uint(int(s.reason), 8, "session reason"), float(s.snr_db),
        check_uint(s.rows, 8, "rows"), check_uint(s.cols, 8, "cols"),
        int(bool(s.running)) | int(bool(s.blind)) << 1,
        check_uint(s.response_window_us, 32, "response window (µs)"),
        check_uint(s.tasks, 16, "posed tasks"), 0, check_uint(s.table_digest, 32, "table digest"))


def stimulus_payload(e: StimulusEntry) -> bytes:
    """The STIMULUS payload of ``e`` (5 + name bytes)."""
    name = e.name.encode("utf-8")
    if not 1 <= len(name) <= MAX_NAME_BYTES:
        raise ProtocolError(f"stimulus name {e.name!r} is {len(name)} UTF-8 bytes: a name on "
                            f"the wire has 1..{MAX_NAME_BYTES}")
    return struct.pack("<IB", check_uint(e.stimulus_id, 32, "stimulus_id"), len(name)) + name


def run_end_payload(r: RunEnd) -> bytes:
    """The 7-byte RUN_END payload of ``r``."""
    return _RUN_END.pack(check_uint(r.t_us, 48, "run end time (µs)").to_bytes(6, "little"),
                         check_uint(int(r.reason), 8, "run end reason"))


def payload_of(record: Session | StimulusEntry | RunEnd) -> tuple[int, bytes]:
    """(kind, payload) of a session record."""
    if isinstance(record, Session):
        return KIND_SESSION, session_payload(record)
    if isinstance(record, StimulusEntry):
        return KIND_STIMULUS, stimulus_payload(record)
    return KIND_RUN_END, run_end_payload(record)


def payload_length(kind: int, head: bytes) -> int:
    """Length of the payload of ``kind`` whose first bytes are ``head`` (-1: not yet known
    or invalid)."""
    if kind == KIND_SESSION:
        return SESSION_BYTES
    if kind == KIND_RUN_END:
        return RUN_END_BYTES
    if kind == KIND_STIMULUS and len(head) >= STIMULUS_HEAD and 1 <= head[4] <= MAX_NAME_BYTES:
        return STIMULUS_HEAD + head[4]
    return -1


def parse(kind: int, p: bytes) -> Session | StimulusEntry | RunEnd | None:
    """The record of a payload (exactly its length), or None if its fields are invalid
    (the same checks as the serial layout check, SPEC.md §6)."""
    if payload_length(kind, p) != len(p):
        return None
    if kind == KIND_SESSION:
        (t, version, n_ch, step, board, tick, n_stim, reason, snr, rows, cols, flags, window,
         tasks, _, digest) = _SESSION.unpack(p)
        if version not in KNOWN_VERSIONS or step == 0 or math.isnan(snr):
            return None
        return Session(int.from_bytes(t, "little"), enum_or_int(SessionReason, reason),
                       version, board, bool(flags & 1), n_ch, rows, cols, step, tick, snr,
                       window, n_stim, digest, tasks, bool(flags & 2))
    if kind == KIND_STIMULUS:
        sid, _ = struct.unpack_from("<IB", p)
        return StimulusEntry(sid, p[STIMULUS_HEAD:].decode("utf-8", errors="replace"))
    t, reason = _RUN_END.unpack(p)
    return RunEnd(int.from_bytes(t, "little"), enum_or_int(RunEndReason, reason))


def table_digest(table: Iterable[StimulusEntry]) -> int:
    """CRC-32 of the STIMULUS payloads in ascending id order (the SESSION's digest)."""
    crc = 0
    for e in sorted(table, key=lambda e: e.stimulus_id):
        crc = zlib.crc32(stimulus_payload(e), crc)
    return crc


def chunks(payload: bytes, fd: bool) -> list[bytes]:
    """The CAN frames' data of ``payload`` without byte 0 (the sequence number, which the
    encoder ORs in): classic ``[chunk index << 4 placeholder]`` is left to the caller;
    returns per frame the bytes after byte 0 (classic: 7 bytes; FD: index byte + 62 bytes),
    zero-padded."""
    size = FD_CHUNK if fd else CLASSIC_CHUNK
    n = max(1, -(-len(payload) // size))
    if n > 16:
        raise ProtocolError(f"a {len(payload)}-byte record does not fit 16 CAN frames")
    out = []
    for i in range(n):
        part = payload[i * size:(i + 1) * size].ljust(size, b"\0")
        out.append(bytes([i]) + part if fd else part)
    return out


class Reassembly:
    """Joins the chunks of session records received in CAN frames (SPEC.md §5.8).

    A record is taken only from chunks 0, 1, ... of one class with consecutive sequence
    numbers; any other arrival discards the partial record (and a chunk that does not start
    one is ignored), as for the classic status group.
    """

    def __init__(self, seq_mod: int) -> None:
        self._seq_mod = seq_mod
        self._cls = -1
        self._seq = -1
        self._data = bytearray()
        self._next = 0

    def add(self, kind: int, index: int, seq: int, chunk: bytes
            ) -> Session | StimulusEntry | RunEnd | None:
        """Take one chunk; return the record it completes, if any."""
        if index == 0:
            self._cls, self._data, self._next = kind, bytearray(), 0
        elif not (kind == self._cls and index == self._next
                  and seq == (self._seq + 1) % self._seq_mod):
            self._cls, self._next = -1, 0
            return None
        self._seq = seq
        self._data += chunk
        self._next += 1
        need = payload_length(kind, bytes(self._data))
        if need < 0:
            self._cls = -1
            return None
        if len(self._data) < need:
            return None
        self._cls = -1
        return parse(kind, bytes(self._data[:need]))
