"""Which recording format a file name selects: the one dispatcher by extension.

A CAN stream is recorded in the standard CAN log formats that python-can both writes
(``can.Logger``) and reads (``can.LogReader``), chosen by the extension through python-can
itself (.asc, .blf, .csv, .log, .trc, .db, .mf4 ...); a serial or UDP stream in the capture
format of SPEC.md "Capture files" (:data:`CAPTURE_SUFFIX`, :mod:`protocols.capture`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from skinhil.errors import ConfigError

CAPTURE_SUFFIX = ".skcap"
"""Extension of a serial / UDP capture file."""

Format = Literal["capture", "can"]

CAN_FD_LOG_SUFFIXES = (".asc", ".blf", ".log", ".mf4")
"""The CAN log formats that keep CAN FD frames as they are (python-can 4.6: .csv and .db
drop the FD flag, .trc writes no FD frame)."""


def can_log_suffixes() -> tuple[str, ...]:
    """The extensions python-can both writes and reads (lower case, with the dot)."""
    from can.io.logger import MESSAGE_WRITERS
    from can.io.player import MESSAGE_READERS

    return tuple(sorted(set(MESSAGE_WRITERS) & set(MESSAGE_READERS)))


def recording_format(path: Path) -> Format:
    """"capture" or "can" by ``path``'s extension; ConfigError for any other."""
    suffix = Path(path).suffix.lower()
    if suffix == CAPTURE_SUFFIX:
        return "capture"
    if suffix in can_log_suffixes():
        return "can"
    raise ConfigError(f"recording '{path}': unknown extension {suffix or '(none)'!r}; give "
                      f"{CAPTURE_SUFFIX} (serial, UDP) or a CAN log "
                      f"({', '.join(can_log_suffixes())})")


def check_link_fits(path: Path, link: str, fd: bool = False) -> Format:
    """The format of ``path`` if it records a ``link`` ("serial", "udp" or "can"; ``fd``:
    CAN FD) stream; ConfigError naming what to do otherwise."""
    fmt = recording_format(path)
    if fmt == "can" and fd and Path(path).suffix.lower() not in CAN_FD_LOG_SUFFIXES:
        raise ConfigError(f"'{path}': python-can's {Path(path).suffix} log does not keep CAN "
                          f"FD frames; use {', '.join(CAN_FD_LOG_SUFFIXES)}")
    if (fmt == "can") != (link == "can"):
        what = "a CAN log" if fmt == "can" else f"a {CAPTURE_SUFFIX} capture"
        use = ("--can CHANNEL" if fmt == "can" else "--port PORT or --udp HOST:PORT")
        raise ConfigError(f"'{path}' is {what}, the link is {link}: use {use}, or a "
                          f"{'CAN log extension' if link == 'can' else CAPTURE_SUFFIX} file")
    return fmt
