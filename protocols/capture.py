"""Capture files of a serial or UDP stream (SPEC.md "Capture files"): writer and reader.

A capture holds exactly what a board handed to its link, unit by unit (the bytes of one
write to a serial port, or one UDP datagram), each stamped with host time (ns since the Unix
epoch) and board time (µs). Pure: works on binary file objects, imports nothing of skinhil.

    header  32 bytes: magic b"SKHLCAP\\n", format version u16, wire version u8, link kind u8
            (1 serial, 2 UDP), step u32 (µs), host start time i64 (ns), reserved u64 (0)
    record  20 bytes + payload: host time i64 (ns), board time i64 (µs), length u32,
            then ``length`` payload bytes (1..MAX_UNIT_BYTES)
    end     20 bytes: host time i64 (ns), record count i64, length 0xFFFFFFFF

A file without its end record, or whose last record is cut short, is truncated.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import BinaryIO

from protocols.constants import KNOWN_VERSIONS
from protocols.errors import ProtocolError

MAGIC = b"SKHLCAP\n"
"""First 8 bytes of every capture file."""
FORMAT_VERSION = 2
"""Version of the capture layout itself (not of the wire stream it holds) that is written."""
READ_FORMAT_VERSIONS = (1, 2)
"""Versions read: 1 without a per-record check, 2 with a CRC-32 per record."""
LINK_KINDS = {"serial": 1, "udp": 2}
"""Link kind codes of the header."""
MAX_UNIT_BYTES = 1 << 20
"""Longest unit (bytes) a record holds; a longer length field means a damaged file."""
END_LENGTH = 0xFFFFFFFF
"""Length field of the end record."""

_HEADER = struct.Struct("<8sHBBIqQ")
_RECORD = struct.Struct("<qqI")
_CRC = struct.Struct("<I")
HEADER_BYTES = _HEADER.size
RECORD_HEADER_BYTES = _RECORD.size + _CRC.size
"""Bytes of a record before its payload (format version 2)."""


@dataclass(frozen=True)
class CaptureHeader:
    """What a capture holds: wire version (3 or 4), link kind ("serial" or "udp"), the
    stream's step (µs) and the host time (ns since the Unix epoch) the capture started."""

    wire_version: int
    link: str
    step_us: int
    start_ns: int
    format_version: int = FORMAT_VERSION

    @property
    def checked(self) -> bool:
        """Whether each record carries a CRC-32 (format version 2 on)."""
        return self.format_version >= 2


@dataclass(frozen=True)
class CaptureUnit:
    """One unit as the board handed it to its link: host time (ns since the Unix epoch),
    board time (µs) and the payload bytes."""

    host_ns: int
    board_us: int
    payload: bytes


class CaptureWriter:
    """Writes a capture to a binary file object as units arrive (nothing kept in memory).

    :meth:`close` writes the end record (it does not close ``f``): a file without it reads
    as truncated.
    """

    def __init__(self, f: BinaryIO, header: CaptureHeader) -> None:
        if header.link not in LINK_KINDS:
            raise ProtocolError(f"capture link kind {header.link!r}: give one of "
                                f"{sorted(LINK_KINDS)}")
        self._f = f
        self.records = 0
        """Records written so far."""
        self._last_ns = header.start_ns
        f.write(_HEADER.pack(MAGIC, FORMAT_VERSION, header.wire_version,
                             LINK_KINDS[header.link], header.step_us, header.start_ns, 0))

    def write(self, host_ns: int, board_us: int, payload: bytes) -> None:
        """Append one unit (1..:data:`MAX_UNIT_BYTES` bytes; an empty one is skipped)."""
        if not payload:
            return
        if len(payload) > MAX_UNIT_BYTES:
            raise ProtocolError(f"a capture unit holds at most {MAX_UNIT_BYTES} bytes, "
                                f"got {len(payload)}: write it in parts")
        head = _RECORD.pack(host_ns, board_us, len(payload))
        self._f.write(head + _CRC.pack(zlib.crc32(payload, zlib.crc32(head))))
        self._f.write(payload)
        self.records += 1
        self._last_ns = host_ns

    def close(self, host_ns: int | None = None) -> None:
        """Write the end record (host time ``host_ns``, default the last unit's)."""
        head = _RECORD.pack(self._last_ns if host_ns is None else host_ns, self.records,
                            END_LENGTH)
        self._f.write(head + _CRC.pack(zlib.crc32(head)))
        self._f.flush()


def read_header(f: BinaryIO) -> CaptureHeader:
    """The header at the start of ``f``; ProtocolError if ``f`` is no capture this reads."""
    raw = f.read(HEADER_BYTES)
    if len(raw) < HEADER_BYTES or raw[:8] != MAGIC:
        raise ProtocolError("not a skinhil capture file (no SKHLCAP header): give a file "
                            "written by skinhil serve --record")
    _, fmt, wire, link, step_us, start_ns, _ = _HEADER.unpack(raw)
    if fmt not in READ_FORMAT_VERSIONS:
        raise ProtocolError(f"capture format version {fmt}: this skinhil reads versions "
                            f"{', '.join(map(str, READ_FORMAT_VERSIONS))}; use the skinhil "
                            "that wrote it")
    if wire not in KNOWN_VERSIONS:
        raise ProtocolError(f"capture of wire version {wire}: this skinhil reads versions "
                            f"{', '.join(map(str, KNOWN_VERSIONS))}; use the skinhil that "
                            "wrote it")
    kinds = {v: k for k, v in LINK_KINDS.items()}
    if link not in kinds:
        raise ProtocolError(f"capture of unknown link kind {link}: the file is damaged")
    if step_us < 1:
        raise ProtocolError("capture with a step of 0 µs: the file is damaged")
    return CaptureHeader(wire, kinds[link], step_us, start_ns, fmt)


def _damaged(count: int) -> ProtocolError:
    return ProtocolError(f"capture damaged in record {count}: its CRC-32 does not match (the "
                         "file changed since it was written); record it again")


def read_units(f: BinaryIO, format_version: int = FORMAT_VERSION) -> Iterator[CaptureUnit]:
    """The units of ``f`` (positioned after the header), one at a time; ``format_version``
    as :func:`read_header` returned it (version 2 records carry a CRC-32, checked).

    Raises ProtocolError at a truncated or damaged record, when the end record is missing,
    or when data follow it (after yielding every whole unit before it).
    """
    checked = format_version >= 2
    head_bytes = RECORD_HEADER_BYTES if checked else _RECORD.size
    count = 0
    while True:
        raw = f.read(head_bytes)
        if len(raw) < head_bytes:
            raise ProtocolError(f"capture truncated after {count} records (no end record): "
                                "the recording was cut short; record it again")
        host_ns, board_us, n = _RECORD.unpack(raw[:_RECORD.size])
        crc = zlib.crc32(raw[:_RECORD.size])
        if n == END_LENGTH:
            if checked and crc != _CRC.unpack(raw[_RECORD.size:])[0]:
                raise _damaged(count)
            if board_us != count or f.read(1):
                raise ProtocolError(f"capture damaged: its end record (counting {board_us} "
                                    f"records, {count} read) does not close the file")
            return
        if not 1 <= n <= MAX_UNIT_BYTES:
            raise ProtocolError(f"capture damaged at record {count}: length {n}")
        payload = f.read(n)
        if len(payload) < n:
            raise ProtocolError(f"capture truncated in record {count}: the recording was "
                                "cut short; record it again")
        if checked and zlib.crc32(payload, crc) != _CRC.unpack(raw[_RECORD.size:])[0]:
            raise _damaged(count)
        count += 1
        yield CaptureUnit(host_ns, board_us, payload)

