"""The master end of a pty pair as a :class:`~skinhil.transports.base.Transport`.

``os.openpty()`` gives a real tty: the slave has a path that any serial program (pyserial,
:class:`~skinhil.transports.serial.SerialTransport`, ``skinhil serve --port``) opens, but the
master end has no path, so pyserial cannot open it. This plugin reads and writes the master's
file descriptor with the same uniform timeouts (None blocks, 0 polls, > 0 deadline, seconds).
The link URL ``pty:?baud=921600`` opens a new pair and announces the slave's path
(docs/links.md).
"""

from __future__ import annotations

import logging
import os
import time
import tty

from skinhil.errors import TransportError
from skinhil.transports.base import (
    DEFAULT_BAUD,
    Deadline,
    Role,
    Transport,
    check_baud,
    read_fd,
    write_fd,
)
from skinhil.transports.url import LinkUrl, format_url

log = logging.getLogger(__name__)


class PtyMasterTransport(Transport[bytes]):
    """Serial bytes over a pty master fd; ``baud`` (bits/s) only sets the wire budget."""

    kind = "serial"
    scheme = "pty"

    def __init__(self, master_fd: int, slave_path: str, baud: int = DEFAULT_BAUD) -> None:
        self.fd = master_fd
        """The master's file descriptor."""
        self.slave_path = slave_path
        self.baud = check_baud(baud)
        self._closed = False
        self._held_slave: int | None = None
        os.set_blocking(master_fd, False)

    @classmethod
    def from_url(cls, url: LinkUrl, role: Role) -> PtyMasterTransport:
        """``pty:?baud=N``: a new pty pair (either role); the slave's path, which the other
        end opens as a serial port, is logged and held in :attr:`slave_path`. The slave fd
        stays open until :meth:`shutdown`, so the master never reads EIO before the other
        end opens it."""
        url.check_options(("baud",))
        if url.target:
            raise TransportError(f"link URL {url}: a pty: link opens a new pair and takes no "
                                 "path: give pty: (the other end opens the announced path "
                                 "with serial:PATH)")
        baud = url.int_option("baud", DEFAULT_BAUD)
        link, slave = cls.open_pair(DEFAULT_BAUD if baud is None else baud)
        link._held_slave = slave
        log.warning("pty link: the other end opens %s", link.slave_path)
        return link

    @property
    def url(self) -> str:
        return format_url("pty", "", baud=self.baud)

    @classmethod
    def open_pair(cls, baud: int = DEFAULT_BAUD) -> tuple[PtyMasterTransport, int]:
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
            return read_fd(self.fd, timeout)
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
        for fd in (self.fd, self._held_slave):
            if fd is None:
                continue
            try:
                os.close(fd)
            except OSError:
                pass
