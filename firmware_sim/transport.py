"""One small interface for the links the board talks over, and its serial and CAN plugins.

Modelled on python-can's ``BusABC``: :meth:`Transport.send`, :meth:`Transport.recv`,
:meth:`Transport.shutdown`, usable as a context manager. Timeouts are uniform, in seconds:
``None`` blocks, ``0`` polls (never blocks), ``> 0`` is a deadline on the monotonic clock.

A serial link carries ``bytes``; a CAN link carries ``list[protocols.CanFrame]``. Both say
how long a payload occupies the real wire (:meth:`Transport.wire_seconds`), so a sender can
pace a pty or a vcan, which have no bit timing, to the baud rate or bitrate it emulates.

These transports know nothing about the board: the board and the receiver both use them.
Errors on open and on a link that goes away are :class:`skinhil.errors.TransportError` with a
one-line message saying what to do.
"""

from __future__ import annotations

import abc
import collections
import errno
import logging
import os
import queue
import select
import socket
import threading
import time
from typing import Any, Generic, TypeVar

from skinhil.errors import TransportError

log = logging.getLogger(__name__)

P = TypeVar("P")

MAX_BAUD = 20_000_000
"""Largest baud rate accepted (bits/s)."""
MAX_CAN_BITRATE = 12_000_000
"""Largest CAN (FD data phase) bitrate accepted (bits/s)."""
CAN_RCVBUF_BYTES = 8 * 1024 * 1024
"""Socket receive buffer requested for a SocketCAN bus (the kernel may cap it)."""
CAN_RX_QUEUE_FRAMES = 1_000_000
"""Frames the CAN reader thread holds before it counts overflows."""


class Transport(abc.ABC, Generic[P]):
    """A link that moves payloads of type ``P`` (``bytes`` or ``list[CanFrame]``)."""

    kind: str = "abstract"
    """"serial" or "can"."""

    @property
    @abc.abstractmethod
    def name(self) -> str:
        """Human-readable name of the link (port or channel)."""

    @abc.abstractmethod
    def send(self, payload: P, timeout: float | None = None) -> int:
        """Send ``payload``; return how many units (bytes or frames) the link accepted.

        ``timeout`` None blocks until all is sent, 0 sends what goes without blocking,
        ``> 0`` sends until the deadline. Raises :class:`TransportError` if the link is gone.
        """

    @abc.abstractmethod
    def recv(self, timeout: float | None = None) -> P:
        """Receive what is available: an empty payload if nothing arrived by the deadline."""

    @abc.abstractmethod
    def wire_seconds(self, payload: P) -> float:
        """Seconds (s) ``payload`` occupies on the real wire at this link's rate."""

    @abc.abstractmethod
    def empty(self) -> P:
        """An empty payload of this link's type."""

    @abc.abstractmethod
    def shutdown(self) -> None:
        """Close the link; idempotent."""

    def __enter__(self) -> Transport[P]:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()


class _Deadline:
    """A timeout in seconds turned into a monotonic deadline (None: no deadline)."""

    def __init__(self, timeout: float | None) -> None:
        if timeout is not None and timeout < 0:
            raise ValueError(f"timeout must be None or >= 0 seconds, got {timeout!r}")
        self.end = None if timeout is None else time.monotonic() + timeout

    def left(self) -> float | None:
        return None if self.end is None else max(0.0, self.end - time.monotonic())


def check_baud(baud: int) -> int:
    """``baud`` if it is a usable baud rate (bits/s), else :class:`TransportError`."""
    if not isinstance(baud, int) or isinstance(baud, bool) or not 50 <= baud <= MAX_BAUD:
        raise TransportError(f"invalid baud rate {baud!r}: give an integer from 50 to "
                             f"{MAX_BAUD} bits/s, e.g. --baud 921600")
    return baud


def check_bitrate(bitrate: int, what: str = "bitrate") -> int:
    """``bitrate`` if it is a usable CAN bitrate (bits/s), else :class:`TransportError`."""
    if (not isinstance(bitrate, int) or isinstance(bitrate, bool)
            or not 1000 <= bitrate <= MAX_CAN_BITRATE):
        raise TransportError(f"invalid CAN {what} {bitrate!r}: give an integer from 1000 to "
                             f"{MAX_CAN_BITRATE} bits/s, e.g. 1000000")
    return bitrate


class SerialTransport(Transport[bytes]):
    """A serial port opened with pyserial: a device path or a URL (``loop://``, ``socket://``).

    ``baud`` (bits/s) configures real UARTs and sets the wire budget: 8N1, 10 bits per byte.
    The port is locked for exclusive use where the OS allows it.
    """

    kind = "serial"

    def __init__(self, port: str, baud: int = 921600) -> None:
        import serial  # pyserial

        self.baud = check_baud(baud)
        self._port_name = port
        self._timeout: float | None = -1.0
        self._write_timeout: float | None = -1.0
        self._closed = False
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

    @property
    def name(self) -> str:
        return self._port_name

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
            return _write_fd(fd, payload, _Deadline(timeout))
        except (serial.SerialTimeoutException, queue.Full):  # URL handlers' write timeout
            return 0
        except (serial.SerialException, OSError) as exc:
            raise TransportError(f"serial port {self._port_name!r} went away: {exc}") from None

    def recv(self, timeout: float | None = None) -> bytes:
        import serial

        self._check_open()
        try:
            self._set_timeout(timeout)
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


def _write_fd(fd: int, payload: bytes, deadline: _Deadline) -> int:
    """Write to a non-blocking fd until done or the deadline; return the bytes written."""
    view = memoryview(payload)
    sent = 0
    while sent < len(view):
        try:
            sent += os.write(fd, view[sent:])
            continue
        except BlockingIOError:
            pass
        except InterruptedError:
            continue
        left = deadline.left()
        if left == 0.0:
            break
        _, ready, _ = select.select([], [fd], [], left)
        if not ready:
            break
    return sent


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


class CanTransport(Transport[list[Any]]):
    """A CAN bus through python-can's ``can.Bus``: any interface (socketcan, virtual, ...).

    ``channel`` and ``interface`` go to ``can.Bus``; ``fd`` enables CAN FD; ``bitrate`` and
    ``data_bitrate`` (bits/s) configure adapters that take them and set the wire budget
    (SocketCAN takes its bitrate from ``ip link``; vcan has none, so the budget is all that
    paces it). A reader thread drains the bus continuously, so the kernel's socket buffer
    never overflows silently; ``rx_overflows`` counts frames the thread had to discard.
    """

    kind = "can"

    def __init__(self, channel: str, interface: str = "socketcan", fd: bool = False,
                 bitrate: int = 1_000_000, data_bitrate: int | None = None) -> None:
        import can

        self.channel = channel
        self.interface = interface
        self.fd = bool(fd)
        self.bitrate = check_bitrate(bitrate)
        self.data_bitrate = None if data_bitrate is None else check_bitrate(
            data_bitrate, "data bitrate")
        if self.data_bitrate is not None and not self.fd:
            raise TransportError("a CAN data bitrate needs CAN FD: add --fd or drop "
                                 "--data-bitrate")
        kwargs: dict[str, Any] = {"channel": channel, "interface": interface, "fd": self.fd,
                                  "bitrate": self.bitrate}
        if self.data_bitrate is not None:
            kwargs["data_bitrate"] = self.data_bitrate
        if interface == "socketcan":
            kwargs.pop("bitrate")
            if not hasattr(socket, "AF_CAN"):
                raise TransportError(_no_can_message(channel))
        can_log = logging.getLogger("can")
        level = can_log.level
        can_log.setLevel(logging.CRITICAL)  # its own error line would repeat ours below
        try:
            self._bus = can.Bus(**kwargs)
        except can.CanInterfaceNotImplementedError as exc:
            raise TransportError(f"CAN interface {interface!r} is not available: {exc}; "
                                 "see python-can's list of interfaces (socketcan, virtual, "
                                 "pcan, kvaser, slcan, ...)") from None
        except OSError as exc:
            if exc.errno in (errno.EAFNOSUPPORT, errno.EPROTONOSUPPORT):
                raise TransportError(_no_can_message(channel)) from None
            if exc.errno == errno.ENODEV:
                raise TransportError(
                    f"CAN channel {channel!r} does not exist: list them with 'ip link show "
                    "type can' / 'ip link show type vcan', or create a virtual one with "
                    f"{_VCAN_HOWTO}") from None
            if exc.errno in (errno.EACCES, errno.EPERM):
                raise TransportError(f"permission denied on CAN channel {channel!r}: "
                                     f"{exc.strerror}") from None
            raise TransportError(f"cannot open CAN channel {channel!r} on {interface!r}: "
                                 f"{exc}") from None
        except (can.CanError, ValueError, TypeError, ImportError) as exc:
            raise TransportError(f"cannot open CAN channel {channel!r} on {interface!r}: "
                                 f"{exc}") from None
        finally:
            can_log.setLevel(level)
        sock = getattr(self._bus, "socket", None)
        if isinstance(sock, socket.socket):
            try:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, CAN_RCVBUF_BYTES)
            except OSError as exc:
                log.debug("SO_RCVBUF on %s: %s", channel, exc)
        self.rx_overflows = 0
        self._rx: collections.deque[Any] = collections.deque()
        self._rx_ready = threading.Condition()
        self._rx_error: Exception | None = None
        self._closed = threading.Event()
        self._reader = threading.Thread(target=self._read_loop, name=f"can-rx-{channel}",
                                        daemon=True)
        self._reader.start()

    @property
    def name(self) -> str:
        return f"{self.interface}:{self.channel}"

    def _read_loop(self) -> None:
        import can

        while not self._closed.is_set():
            try:
                msg = self._bus.recv(0.05)
            except (can.CanError, OSError, ValueError) as exc:
                if not self._closed.is_set():
                    self._rx_error = exc
                with self._rx_ready:
                    self._rx_ready.notify_all()
                return
            if msg is None or msg.is_error_frame or msg.is_remote_frame:
                continue
            frame = _frame_from_message(msg)
            with self._rx_ready:
                if len(self._rx) >= CAN_RX_QUEUE_FRAMES:
                    self.rx_overflows += 1
                    continue
                self._rx.append(frame)
                self._rx_ready.notify()

    def send(self, payload: list[Any], timeout: float | None = None) -> int:
        import can

        if self._closed.is_set():
            raise TransportError(f"CAN channel {self.channel!r} is closed")
        deadline = _Deadline(timeout)
        sent = 0
        for frame in payload:
            msg = _message_from_frame(frame, self.data_bitrate is not None)
            while True:
                try:
                    self._bus.send(msg, timeout=deadline.left())
                    break
                except can.CanOperationError as exc:
                    if exc.error_code in (errno.ENOBUFS, errno.EAGAIN) or "Transmit buffer" \
                            in str(exc) or "timed out" in str(exc).lower():
                        left = deadline.left()
                        if left == 0.0:
                            return sent
                        time.sleep(min(0.0005, left) if left is not None else 0.0005)
                        continue
                    raise TransportError(f"CAN channel {self.channel!r} went away: "
                                         f"{exc}") from None
                except (can.CanError, OSError) as exc:
                    raise TransportError(f"CAN channel {self.channel!r} went away: "
                                         f"{exc}") from None
            sent += 1
        return sent

    def recv(self, timeout: float | None = None) -> list[Any]:
        if self._closed.is_set():
            raise TransportError(f"CAN channel {self.channel!r} is closed")
        deadline = _Deadline(timeout)
        with self._rx_ready:
            while not self._rx:
                if self._rx_error is not None:
                    raise TransportError(f"CAN channel {self.channel!r} went away: "
                                         f"{self._rx_error}")
                left = deadline.left()
                if left == 0.0 or self._closed.is_set():
                    return []
                self._rx_ready.wait(left)
            out = list(self._rx)
            self._rx.clear()
        return out

    def wire_seconds(self, payload: list[Any]) -> float:
        from protocols import can_frame_seconds

        return float(sum(can_frame_seconds(f, self.bitrate, self.data_bitrate) for f in payload))

    def empty(self) -> list[Any]:
        return []

    def shutdown(self) -> None:
        if self._closed.is_set():
            return
        self._closed.set()
        self._reader.join(timeout=1.0)
        with self._rx_ready:
            self._rx_ready.notify_all()
        try:
            self._bus.shutdown()
        except Exception as exc:  # a vanished adapter may fail to close; nothing to recover
            log.debug("closing %s: %s", self.channel, exc)


_VCAN_HOWTO = ("'sudo modprobe vcan && sudo ip link add dev vcan0 type vcan && "
               "sudo ip link set up vcan0'")


def _no_can_message(channel: str) -> str:
    return (f"cannot open CAN channel {channel!r}: this system has no SocketCAN support "
            f"(socket.AF_CAN unavailable); on Linux create a virtual bus with {_VCAN_HOWTO}, "
            "or choose another python-can interface with --interface (e.g. virtual)")


def _message_from_frame(frame: Any, bitrate_switch: bool) -> Any:
    import can

    ext = getattr(frame, "is_extended_id", None)
    if ext is None:
        ext = frame.arbitration_id > 0x7FF
    return can.Message(arbitration_id=frame.arbitration_id, data=frame.data,
                       is_extended_id=bool(ext), is_fd=bool(frame.is_fd),
                       bitrate_switch=bool(frame.is_fd and bitrate_switch),
                       check=False)


def _frame_from_message(msg: Any) -> Any:
    from protocols import CanFrame

    kwargs: dict[str, Any] = {}
    if "is_extended_id" in getattr(CanFrame, "__dataclass_fields__", {}):
        kwargs["is_extended_id"] = bool(msg.is_extended_id)
    return CanFrame(arbitration_id=int(msg.arbitration_id), data=bytes(msg.data),
                    is_fd=bool(msg.is_fd), **kwargs)


__all__ = ["CanTransport", "SerialTransport", "Transport", "check_baud", "check_bitrate"]
