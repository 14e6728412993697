"""The payloads of the session records (SPEC.md §3.7): SESSION, STIMULUS, RUN_END, SUITE and
TASK.

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

import numpy as np

from protocols.constants import KNOWN_VERSIONS
from protocols.errors import ProtocolError
from protocols.record_fields import check_uint, enum_or_int
from protocols.records import (
    RunEnd,
    RunEndReason,
    Session,
    SessionReason,
    SessionRecord,
    StimulusEntry,
    SuiteEntry,
    Task,
    TaskEntry,
)

KIND_SESSION, KIND_STIMULUS, KIND_RUN_END, KIND_SUITE, KIND_TASK = 0, 1, 2, 3, 4
"""Serial type-7 kinds (byte 0 bits 4..0); kinds 5..31 are reserved for future records."""

CLASS_OF_KIND = {KIND_SESSION: 8, KIND_STIMULUS: 9, KIND_RUN_END: 10, KIND_SUITE: 11,
                 KIND_TASK: 12}
"""CAN frame class of each kind (ID = class << 4 | board id); classes 13..15 are reserved."""

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
SUITE_HEAD = 5
"""A SUITE payload: version (u16), task records that follow (u8), name length n (u8), case
length m (u8), then the n name bytes and the m case bytes."""
SUITE_FIELDS: tuple[tuple[str, int, int], ...] = (
    ("SuiteVersion", 0, 2), ("NTasks", 2, 1), ("NameLength", 3, 1), ("CaseLength", 4, 1))
"""(DBC signal name, payload offset, bytes) of the SUITE's fixed fields."""
MAX_SUITE_NAME_BYTES = 32
"""Longest suite or case name on the wire (UTF-8 bytes)."""
TASK_HEAD = 7
"""A TASK payload: task id (u8), class count k (u8), tolerance (binary32), unit length u (u8),
then the u unit bytes and k binary32 classes."""
TASK_FIELDS: tuple[tuple[str, int, int], ...] = (
    ("Task", 0, 1), ("NClasses", 1, 1), ("Tolerance", 2, 4), ("UnitLength", 6, 1))
"""(DBC signal name, payload offset, bytes) of the TASK's fixed fields."""
MAX_UNIT_BYTES = 8
"""Longest unit symbol on the wire (UTF-8 bytes)."""
MAX_CLASSES = 24
"""Most classes of one TASK record (its payload then fits 16 classic CAN chunks)."""


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
        int(bool(s.running)) | int(bool(s.blind)) << 1 | int(bool(s.held_object)) << 2,
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


def _name_bytes(text: str, most: int, what: str) -> bytes:
    """``text`` in UTF-8, refused if longer than ``most`` bytes."""
    raw = text.encode("utf-8")
    if len(raw) > most:
        raise ProtocolError(f"{what} {text!r} is {len(raw)} UTF-8 bytes: at most {most} on "
                            "the wire")
    return raw


def suite_payload(e: SuiteEntry) -> bytes:
    """The SUITE payload of ``e`` (5 + name + case bytes)."""
    name = _name_bytes(e.name, MAX_SUITE_NAME_BYTES, "suite name")
    case = _name_bytes(e.case, MAX_SUITE_NAME_BYTES, "suite case")
    if (not name) != (not case) or (not name and e.version):
        raise ProtocolError(f"suite {e.name!r} case {e.case!r} version {e.version}: give a "
                            "name, a case and a version, or none of them (no suite)")
    return struct.pack("<HBBB", check_uint(e.version, 16, "suite version"),
                       check_uint(e.n_tasks, 8, "task records"), len(name), len(case)
                       ) + name + case


def task_payload(e: TaskEntry) -> bytes:
    """The TASK payload of ``e`` (7 + unit bytes + 4 per class)."""
    tol = 0.0 if e.tolerance is None or e.tolerance == 0 else float(e.tolerance)
    if not (math.isfinite(tol) and tol >= 0):
        raise ProtocolError(f"task {e.task} tolerance {e.tolerance!r}: give a finite value "
                            ">= 0, or None for none")
    if tol > 0 and struct.unpack("<f", struct.pack("<f", tol))[0] == 0:
        raise ProtocolError(f"task {e.task} tolerance {tol!r} is 0 in binary32: give a larger "
                            "one, or None for none")
    unit = _name_bytes(e.unit, MAX_UNIT_BYTES, "task unit")
    if len(e.classes) > MAX_CLASSES:
        raise ProtocolError(f"task {e.task} has {len(e.classes)} classes: at most "
                            f"{MAX_CLASSES} on the wire")
    if any(math.isnan(float(c)) for c in e.classes):
        raise ProtocolError(f"task {e.task} has a NaN class; give numbers")
    return (struct.pack("<BBfB", check_uint(int(e.task), 4, "task id"), len(e.classes), tol,
                        len(unit)) + unit
            + struct.pack(f"<{len(e.classes)}f", *map(float, e.classes)))


def payload_of(record: SessionRecord) -> tuple[int, bytes]:
    """(kind, payload) of a session record."""
    if isinstance(record, Session):
        return KIND_SESSION, session_payload(record)
    if isinstance(record, StimulusEntry):
        return KIND_STIMULUS, stimulus_payload(record)
    if isinstance(record, SuiteEntry):
        return KIND_SUITE, suite_payload(record)
    if isinstance(record, TaskEntry):
        return KIND_TASK, task_payload(record)
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
    if (kind == KIND_SUITE and len(head) >= SUITE_HEAD and head[3] <= MAX_SUITE_NAME_BYTES
            and head[4] <= MAX_SUITE_NAME_BYTES):
        return SUITE_HEAD + head[3] + head[4]
    if (kind == KIND_TASK and len(head) >= TASK_HEAD and head[1] <= MAX_CLASSES
            and head[6] <= MAX_UNIT_BYTES):
        return TASK_HEAD + head[6] + 4 * head[1]
    return -1


def parse(kind: int, p: bytes) -> SessionRecord | None:
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
                       window, n_stim, digest, tasks, bool(flags & 2), bool(flags & 4))
    if kind == KIND_STIMULUS:
        sid, _ = struct.unpack_from("<IB", p)
        return StimulusEntry(sid, p[STIMULUS_HEAD:].decode("utf-8", errors="replace"))
    if kind == KIND_SUITE:
        return _parse_suite(p)
    if kind == KIND_TASK:
        return _parse_task(p)
    t, reason = _RUN_END.unpack(p)
    return RunEnd(int.from_bytes(t, "little"), enum_or_int(RunEndReason, reason))


def _parse_suite(p: bytes) -> SuiteEntry | None:
    """The SUITE of payload ``p`` (its length checked), None if its fields are invalid."""
    version, n_tasks, n, m = struct.unpack_from("<HBBB", p)
    if (n == 0) != (m == 0) or (n == 0 and version):
        return None
    name = p[SUITE_HEAD:SUITE_HEAD + n].decode("utf-8", errors="replace")
    case = p[SUITE_HEAD + n:].decode("utf-8", errors="replace")
    return SuiteEntry(name, version, case, n_tasks)


def _parse_task(p: bytes) -> TaskEntry | None:
    """The TASK of payload ``p`` (its length checked), None if its fields are invalid."""
    task, k, tol_bits, u = struct.unpack_from("<BBIB", p)
    if task > 15 or tol_bits >= 0x7F800000:  # the tolerance: finite and >= 0 (no sign bit)
        return None
    tol = _shortest(struct.unpack("<f", struct.pack("<I", tol_bits))[0])
    classes = struct.unpack_from(f"<{k}f", p, TASK_HEAD + u)
    if any(math.isnan(c) for c in classes):
        return None
    return TaskEntry(enum_or_int(Task, task), None if tol == 0 else tol,
                     p[TASK_HEAD:TASK_HEAD + u].decode("utf-8", errors="replace"),
                     tuple(_shortest(c) for c in classes))


def _shortest(value: float) -> float:
    """The binary32 ``value`` as the shortest decimal that encodes to it again (0.05, not
    0.0500000007)."""
    return float(str(np.float32(value)))


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

    def add(self, kind: int, index: int, seq: int, chunk: bytes) -> SessionRecord | None:
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
