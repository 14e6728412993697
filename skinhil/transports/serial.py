"""Serial links through pyserial: a device path (``/dev/ttyUSB0``, a pty) or a URL.

URLs are pyserial's (``loop://``, ``socket://host:port``, ``rfc2217://``, ...). As a link
URL: ``serial:/dev/ttyUSB0?baud=921600``, ``serial:loop://`` (docs/links.md).
"""

from __future__ import annotations

import errno
import logging
import os
import queue
import sys

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

LOCK_DIRS: tuple[str, ...] = ("/var/lock", "/run/lock")
"""Where programs that follow the UUCP convention (minicom, cu, ModemManager, ...) leave
``LCK..<device>`` files holding their process id."""


def uucp_lock_holder(port: str) -> tuple[int, str] | None:
    """(pid, lock file) of another live process holding device ``port`` by a UUCP lock file
    (``LCK..ttyUSB0``; ``LCK..pts_3`` or ``LCK..3`` for ``/dev/pts/3``), else None. A lock
    of a process that no longer exists is stale and ignored; URLs have no lock files."""
    if "://" in port:
        return None
    real = os.path.realpath(port)
    rel = real[len("/dev/"):] if real.startswith("/dev/") else os.path.basename(real)
    names = {f"LCK..{os.path.basename(real)}", f"LCK..{rel.replace('/', '_')}"}
    seen = set()
    for folder in LOCK_DIRS:
        for name in sorted(names):
            path = os.path.join(folder, name)
            if os.path.realpath(path) in seen:
                continue
            seen.add(os.path.realpath(path))
            try:
                with open(path, "rb") as f:
                    raw = f.read(64)
            except OSError:
                continue
            pid = _lock_pid(raw)
            if pid is not None and pid != os.getpid() and _process_exists(pid):
                return pid, path
            log.info("ignoring stale lock file %s", path)
    return None


def _lock_pid(raw: bytes) -> int | None:
    """The process id in a UUCP lock file: ASCII (HDB, the common form) or a 4-byte int."""
    text = raw.strip()
    if text.isdigit():
        return int(text)
    if len(raw) == 4:
        return int.from_bytes(raw, sys.byteorder)
    return None


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    except OSError:
        return False
    return pid > 0


class SerialTransport(Transport[bytes]):
    """A serial port opened with pyserial: a device path or a URL (``loop://``, ``socket://``).

    ``baud`` (bits/s) configures real UARTs and sets the wire budget: 8N1, 10 bits per byte.
    The port is locked for exclusive use where the OS allows it.
    """

    kind = "serial"
    scheme = "serial"

    def __init__(self, port: str, baud: int = DEFAULT_BAUD) -> None:
        import serial  # pyserial

        self.baud = check_baud(baud)
        self._port_name = port
        self._timeout: float | None = -1.0
        self._write_timeout: float | None = -1.0
        self._closed = False
        holder = uucp_lock_holder(port)
        if holder is not None:
            pid, lock = holder
            raise TransportError(f"serial port {port!r} is busy: process {pid} holds it (UUCP "
                                 f"lock file {lock}) — stop that program, or remove the lock "
                                 "file if it is stale")
        try:
            self._ser = serial.serial_for_url(port, baudrate=self.baud, timeout=0,
                                              write_timeout=0, exclusive=True)
        except ValueError as exc:
            raise TransportError(f"cannot open serial port {port!r}: {exc}; give a device "
                                 "path such as /dev/ttyUSB0 or a pyserial URL such as "
                                 "loop://") from None
        except serial.SerialException as exc:
            raise TransportError(_serial_open_message(port, exc)) from None
        except OSError as exc:
            raise TransportError(_serial_open_message(port, exc)) from None

    @classmethod
    def from_url(cls, url: LinkUrl, role: Role) -> SerialTransport:
        """``serial:PORT?baud=N``: PORT a device path or a pyserial URL; either role."""
        url.check_options(("baud",))
        baud = url.int_option("baud", DEFAULT_BAUD)
        return cls(url.require_target("serial:/dev/ttyUSB0?baud=921600 or serial:loop://"),
                   DEFAULT_BAUD if baud is None else baud)

    @property
    def name(self) -> str:
        return self._port_name

    @property
    def url(self) -> str:
        return format_url("serial", self._port_name, baud=self.baud)

    def _set_timeout(self, timeout: float | None) -> None:
        if timeout != self._timeout:
            self._ser.timeout = timeout
            self._timeout = timeout

    def _set_write_timeout(self, timeout: float | None) -> None:
        if timeout != self._write_timeout:
            self._ser.write_timeout = timeout
            self._write_timeout = timeout

    def send(self, payload: bytes, timeout: float | None = None) -> int:
        import serial

        self._check_open()
        if not payload:
            return 0
        fd = getattr(self._ser, "fd", None)
        try:
            if not isinstance(fd, int):  # pyserial URL handlers (loop://, socket://, ...)
                # their write_timeout=0 means "fail unless instant" (loop:// sleeps, then
                # raises), so a poll hands the data over as a blocking write would
                self._set_write_timeout(None if timeout == 0 else timeout)
                return int(self._ser.write(payload) or 0)
            return write_fd(fd, payload, Deadline(timeout))
        except (serial.SerialTimeoutException, queue.Full):  # URL handlers' write timeout
            return 0
        except (serial.SerialException, OSError) as exc:
            raise TransportError(f"serial port {self._port_name!r} went away: {exc}") from None

    def recv(self, timeout: float | None = None) -> bytes:
        import serial

        self._check_open()
        fd = getattr(self._ser, "fd", None)
        try:
            if isinstance(fd, int):  # a device: one select and one read
                return read_fd(fd, timeout)
            self._set_timeout(timeout)  # pyserial URL handlers (loop://, socket://, ...)
            first = self._ser.read(1)
            if not first:
                return b""
            waiting = self._ser.in_waiting
            if not waiting:
                return bytes(first)
            self._set_timeout(0)
            return bytes(first) + bytes(self._ser.read(waiting))
        except (serial.SerialException, OSError) as exc:
            raise TransportError(f"serial port {self._port_name!r} went away: {exc}") from None

    def wire_seconds(self, payload: bytes) -> float:
        from protocols import serial_seconds

        return float(serial_seconds(len(payload), self.baud))

    def empty(self) -> bytes:
        return b""

    def _check_open(self) -> None:
        if self._closed:
            raise TransportError(f"serial port {self._port_name!r} is closed")

    def shutdown(self) -> None:
        self._closed = True
        try:
            self._ser.close()
        except Exception as exc:  # closing a vanished device may fail; nothing to recover
            log.debug("closing %s: %s", self._port_name, exc)


def _serial_open_message(port: str, exc: Exception) -> str:
    code = getattr(exc, "errno", None)
    text = str(exc)
    if code == errno.ENOENT or "No such file" in text:
        return (f"serial port {port!r} not found: check the device path (ls /dev/ttyUSB* "
                "/dev/ttyACM*) or give a pyserial URL such as loop://")
    if code in (errno.EACCES, errno.EPERM) or "Permission denied" in text:
        return (f"permission denied opening serial port {port!r}: add your user to the "
                "dialout group (sudo usermod -aG dialout $USER, then log in again)")
    if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK) or "lock" in text:
        return (f"serial port {port!r} is busy (another program has it open): close that "
                "program or choose another port")
    if "Inappropriate ioctl" in text or code == errno.ENOTTY:
        return f"{port!r} is not a serial port (not a tty): give a serial device or a pty"
    return f"cannot open serial port {port!r}: {text}"
