"""The master end of a pty pair as a :class:`~skinhil.transports.base.Transport`.

``os.openpty()`` gives a real tty: the slave has a path that any serial program (pyserial,
:class:`~skinhil.transports.serial.SerialTransport`, ``skinhil serve --port``) opens, but the
master end has no path, so pyserial cannot open it. This plugin reads and writes the master's
file descriptor with the same uniform timeouts (None blocks, 0 polls, > 0 deadline, seconds).
"""

from __future__ import annotations

import os
import select
import time
import tty

from skinhil.errors import TransportError
from skinhil.transports.base import Deadline, Transport, check_baud, write_fd

READ_CHUNK = 65536
"""Most bytes one :meth:`PtyMasterTransport.recv` returns."""


class PtyMasterTransport(Transport[bytes]):
    """Serial bytes over a pty master fd; ``baud`` (bits/s) only sets the wire budget."""

    kind = "serial"

    def __init__(self, master_fd: int, slave_path: str, baud: int = 921600) -> None:
        self.fd = master_fd
        self.slave_path = slave_path
        self.baud = check_baud(baud)
        self._closed = False
        os.set_blocking(master_fd, False)

    @classmethod
    def open_pair(cls, baud: int = 921600) -> tuple[PtyMasterTransport, int]:
        """A new raw pty pair: (master transport, slave fd); the slave's path is
        ``transport.slave_path``. Keep the slave fd open while the link is in use."""
        master, slave = os.openpty()
        tty.setraw(slave)
        tty.setraw(master)
        return cls(master, os.ttyname(slave), baud), slave

    @property
    def name(self) -> str:
        return f"pty master of {self.slave_path}"

    def _check_open(self) -> None:
        if self._closed:
            raise TransportError(f"pty master of {self.slave_path} is closed")

    def send(self, payload: bytes, timeout: float | None = None) -> int:
        self._check_open()
        try:
            return write_fd(self.fd, payload, Deadline(timeout))
        except OSError as exc:
            raise TransportError(f"pty {self.slave_path} went away: {exc}") from None

    def recv(self, timeout: float | None = None) -> bytes:
        self._check_open()
        try:
            ready, _, _ = select.select([self.fd], [], [], timeout)
            if not ready:
                return b""
            return os.read(self.fd, READ_CHUNK)
        except BlockingIOError:
            return b""
        except OSError as exc:  # EIO: no process has the slave open (yet, or any more)
            if timeout:
                time.sleep(min(timeout, 0.01))
            raise TransportError(f"pty {self.slave_path}: the other end is closed ({exc})") \
                from None

    def wire_seconds(self, payload: bytes) -> float:
        from protocols import serial_seconds

        return float(serial_seconds(len(payload), self.baud))

    def empty(self) -> bytes:
        return b""

    def shutdown(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            os.close(self.fd)
        except OSError:
            pass
