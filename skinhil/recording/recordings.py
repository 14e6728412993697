"""Reading a recording for replay: a capture file (serial, UDP) or a CAN log, checked whole
before a single unit is played.

:func:`open_recording` reads the file through once (bounded memory) and refuses, with one
line saying what to do, a file that is truncated, damaged, not a recording, of a wire
version this skinhil does not read, or that mixes boards or CAN and CAN FD frames.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import protocols
from protocols import can_kernels as ck
from protocols.capture import read_header, read_units
from protocols.constants import KNOWN_VERSIONS, MAX_CAN_CLASS
from skinhil.errors import ConfigError, ProtocolError
from skinhil.recording.formats import recording_format

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Recording:
    """A checked recording: what it holds and how to read its units again."""

    path: Path
    link: str
    """"serial", "udp" or "can": the kind of link it was recorded on."""
    wire_version: int | None
    """3 or 4; None for a CAN log whose frames hold no SYNC."""
    units: int
    """Writes / datagram sends (capture) or frames (CAN log)."""
    duration_s: float
    """Host time (s) from the first unit to the last."""
    fd: bool = False
    """CAN FD frames (CAN logs)."""
    board_id: int = 0
    """The board whose frames a CAN log holds."""

    def read(self) -> Iterator[tuple[float, Any]]:
        """Each unit as (host time s since the Unix epoch, payload): bytes for a capture, one
        :class:`protocols.CanFrame` for a CAN log."""
        if self.link == "can":
            for msg in _can_messages(self.path):
                yield msg.timestamp, protocols.CanFrame(msg.arbitration_id, bytes(msg.data),
                                                        bool(msg.is_fd))
            return
        with open(self.path, "rb") as f:
            header = read_header(f)
            for unit in read_units(f, header.format_version):
                yield unit.host_ns * 1e-9, unit.payload


def _can_messages(path: Path) -> Iterator[Any]:
    import can

    try:
        yield from can.LogReader(str(path))
    except Exception as exc:  # python-can's parsers raise many kinds on a damaged file
        raise ProtocolError(f"CAN log '{path}' cannot be read ({type(exc).__name__}: "
                            f"{exc}): the file is damaged or not a CAN log") from None


def _sync_version(frame: Any) -> int:
    """The version a SYNC frame announces (SPEC.md §5.4, §9)."""
    if frame.is_fd:
        return frame.data[1] >> 4 if len(frame.data) > 1 else 0
    return 4 if frame.data and frame.data[0] & 0x80 else 3


def _check_can_log(path: Path) -> Recording:
    boards: set[int] = set()
    fd_kinds: set[bool] = set()
    versions: set[int] = set()
    n = 0
    first = last = 0.0
    for msg in _can_messages(path):
        if msg.is_extended_id or not ck.CLS_ACK <= msg.arbitration_id >> 4 <= MAX_CAN_CLASS:
            raise ProtocolError(f"CAN log '{path}' holds frame 0x{msg.arbitration_id:X}, "
                                "which no skinhil board sends: record it with skinhil serve "
                                "--record")
        boards.add(msg.arbitration_id & 0xF)
        fd_kinds.add(bool(msg.is_fd))
        if msg.arbitration_id >> 4 == ck.CLS_SYNC:
            versions.add(_sync_version(msg))
        first = msg.timestamp if n == 0 else first
        last = msg.timestamp
        n += 1
    if n == 0:
        raise ProtocolError(f"CAN log '{path}' holds no frames: the file is empty, damaged "
                            "or not a CAN log")
    if len(boards) > 1 or len(fd_kinds) > 1:
        raise ProtocolError(f"CAN log '{path}' mixes boards {sorted(boards)} or CAN and CAN "
                            "FD frames: replay one board's recording")
    unknown = versions - set(KNOWN_VERSIONS)
    if unknown:
        raise ProtocolError(f"CAN log '{path}' is of wire version {min(unknown)}: this "
                            f"skinhil plays versions {', '.join(map(str, KNOWN_VERSIONS))}")
    return Recording(path, "can", max(versions) if versions else None, n,
                     max(0.0, last - first), fd=fd_kinds.pop(), board_id=boards.pop())


def _check_capture(path: Path) -> Recording:
    count = first = last = 0
    try:
        with open(path, "rb") as f:
            header = read_header(f)
            for unit in read_units(f, header.format_version):
                first = unit.host_ns if count == 0 else first
                last = unit.host_ns
                count += 1
    except ProtocolError as exc:
        raise ProtocolError(f"'{path}': {exc}") from None
    if count == 0:
        raise ProtocolError(f"capture '{path}' holds no data: record a longer session")
    if not header.checked:
        log.warning("capture '%s' is of format version %d: its records carry no CRC-32, so "
                    "damage to it is found only where the wire's own CRC finds it",
                    path, header.format_version)
    return Recording(path, header.link, header.wire_version, count, (last - first) * 1e-9)


def open_recording(path: Path) -> Recording:
    """``path`` checked whole (a capture or a CAN log, by its extension).

    Raises ConfigError (no such file, unknown extension) or ProtocolError (truncated,
    damaged, another wire version, not a recording), each one line saying what to do.
    """
    path = Path(path).expanduser()
    fmt = recording_format(path)
    if not path.is_file():
        raise ConfigError(f"recording '{path}' does not exist: give a file written by "
                          "skinhil serve --record")
    try:
        return _check_can_log(path) if fmt == "can" else _check_capture(path)
    except OSError as exc:
        raise ConfigError(f"recording '{path}' cannot be read: {exc.strerror or exc}") \
            from None
