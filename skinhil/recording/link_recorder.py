"""Recording what a board puts on its link, as it goes (``serve --record FILE``).

:class:`RecordingTransport` wraps the board's transport: every unit the link accepts (the
bytes of one serial write, the datagrams of one UDP send, each CAN frame) is written at
once, stamped with host time and board time, to a capture file (serial, UDP) or a CAN log
(:mod:`skinhil.recording.formats`). Nothing is kept in memory; the file is written under a
temporary name and renamed when the recording ends (:func:`skinhil.output_files.atomic_path`),
so a killed run leaves the previous file intact.
"""

from __future__ import annotations

import abc
import contextlib
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

from protocols.capture import CaptureHeader, CaptureWriter
from skinhil.errors import ConfigError
from skinhil.output_files import atomic_path
from skinhil.recording.formats import check_link_fits
from skinhil.transports import Transport
from skinhil.transports.base import WrappedTransport

FLUSH_PERIOD_NS = 500_000_000
"""A capture's buffered units go to the file at least this often (ns of host time, while
units arrive): a killed run's partial file holds all but the last moments."""


class LinkRecorder(abc.ABC):
    """Where recorded units go: :meth:`write` each as it is accepted by the link."""

    units = 0
    """Units (writes, sends or frames) recorded so far."""
    error: OSError | None = None
    """The write error that ended the recording (a full disk), None while it is written:
    :func:`link_recorder` raises it as the block ends."""

    @abc.abstractmethod
    def write(self, payload: Any, board_us: int) -> None:
        """Record ``payload`` (bytes, or a list of :class:`protocols.CanFrame`) handed to the
        link now, at board time ``board_us`` (µs)."""


class CaptureRecorder(LinkRecorder):
    """Serial and UDP units into a capture file (:mod:`protocols.capture`)."""

    def __init__(self, f: BinaryIO, header: CaptureHeader) -> None:
        self._f = f
        self._writer = CaptureWriter(f, header)
        self._flushed_ns = header.start_ns

    def write(self, payload: Any, board_us: int) -> None:
        if payload:
            now = time.time_ns()
            self._writer.write(now, board_us, bytes(payload))
            self.units += 1
            if now - self._flushed_ns > FLUSH_PERIOD_NS:  # on disk within about this much
                self._f.flush()
                self._flushed_ns = now

    def close(self) -> None:
        self._writer.close(time.time_ns())


class CanLogRecorder(LinkRecorder):
    """CAN frames into a python-can log (``can.Logger``: the format by the extension); each
    entry's timestamp is the host time (s since the Unix epoch) it went to the bus."""

    def __init__(self, path: Path) -> None:
        import can

        self._can = can
        try:
            self._logger = can.Logger(str(path))
        except (NotImplementedError, ImportError, ValueError, OSError) as exc:
            raise ConfigError(f"cannot write a {path.suffix} CAN log: {exc}") from None

    def write(self, payload: Any, board_us: int) -> None:
        now = time.time()
        for frame in payload:
            self._logger.on_message_received(self._can.Message(
                timestamp=now, arbitration_id=frame.arbitration_id, data=frame.data,
                is_fd=frame.is_fd, is_extended_id=False, is_rx=False,
                dlc=len(frame.data)))
            self.units += 1

    def close(self) -> None:
        self._logger.stop()


@contextlib.contextmanager
def link_recorder(path: Path, link: str, wire_version: int, step_us: int, fd: bool = False
                  ) -> Iterator[LinkRecorder]:
    """A recorder of a ``link`` ("serial", "udp" or "can"; ``fd``: CAN FD) stream into
    ``path``, renamed into place when the block ends without an exception.

    ``wire_version`` (3 or 4) and ``step_us`` (µs) go into a capture's header. Raises
    ConfigError before anything is written when the extension does not fit the link.
    """
    fmt = check_link_fits(path, link, fd)
    with atomic_path(Path(path)) as tmp:
        if fmt == "can":
            can_rec = CanLogRecorder(tmp)
            try:
                yield can_rec
            finally:
                with (contextlib.suppress(OSError) if can_rec.error is not None
                      else contextlib.nullcontext()):
                    can_rec.close()  # a log that failed to write may fail to close
            if can_rec.error is not None:
                raise can_rec.error
        else:
            with open(tmp, "wb") as f:
                cap = CaptureRecorder(f, CaptureHeader(wire_version, link, step_us,
                                                       time.time_ns()))
                yield cap
                if cap.error is not None:
                    raise cap.error
                cap.close()


class RecordingTransport(WrappedTransport[Any]):
    """``inner`` with every unit it accepts written to ``recorder``; ``board_time_us()``
    gives the board time (µs) each is stamped with. Everything else is ``inner``'s.

    A recording that cannot be written (a full disk) ends the run once, never twice: the
    send whose unit could not be recorded still returns what the link accepted (the board's
    account stays exact), the next send raises the writer's ``OSError`` (the recorder's
    ``error``) before sending, and every send after that goes to the link unrecorded, so the
    board's closing STATUS and RUN_END still reach the receiver and the error is the only one
    reported (:func:`link_recorder` raises it if no send did).
    """

    def __init__(self, inner: Transport[Any], recorder: LinkRecorder,
                 board_time_us: Callable[[], int]) -> None:
        super().__init__(inner)
        self.recorder = recorder
        self._board_time_us = board_time_us
        self._raised = False

    def send(self, payload: Any, timeout: float | None = None) -> int:
        error = self.recorder.error
        if error is not None and not self._raised:
            self._raised = True
            raise error
        n = self.inner.send(payload, timeout)
        if n and error is None:
            try:
                self.recorder.write(payload[:n], self._board_time_us())
            except OSError as exc:
                self.recorder.error = exc
        return n
