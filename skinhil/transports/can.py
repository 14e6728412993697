"""CAN and CAN FD links through python-can's ``can.Bus``: socketcan, virtual, vendor adapters.

As a link URL: ``can:vcan0?interface=socketcan&fd=1&bitrate=1000000&data_bitrate=2000000``
(docs/links.md).
"""

from __future__ import annotations

import collections
import errno
import json
import logging
import socket
import threading
import time
from collections.abc import Mapping
from typing import Any

from skinhil.errors import TransportError
from skinhil.transports.base import Deadline, Role, Transport, check_bitrate
from skinhil.transports.socket_buffer import request_receive_buffer
from skinhil.transports.url import LinkUrl, format_url

log = logging.getLogger(__name__)

CAN_RCVBUF_BYTES = 8 * 1024 * 1024
"""Socket receive buffer requested for a SocketCAN bus (the kernel may cap it)."""
DEFAULT_CAN_BITRATE = 1_000_000
"""Default CAN (arbitration phase) bitrate (bits/s)."""
DEFAULT_CAN_INTERFACE = "socketcan"
"""python-can interface used when neither the caller nor python-can's own configuration
(``CAN_INTERFACE``, ``~/.canrc``, ``can.rc``) names one."""
OWN_BUS_KEYS = ("channel", "interface", "fd", "bitrate", "data_bitrate")
"""``can.Bus`` arguments the link sets itself: extra bus keyword arguments may not give them."""
CAN_RX_QUEUE_FRAMES = 1_000_000
"""Frames the CAN reader thread holds before it counts overflows."""


class CanTransport(Transport[list[Any]]):
    """A CAN bus through python-can's ``can.Bus``: any interface (socketcan, virtual, ...).

    ``channel`` and ``interface`` go to ``can.Bus``; ``interface`` None (and ``bitrate``
    None) take python-can's own configuration (``CAN_INTERFACE`` / ``CAN_BITRATE``,
    ``~/.canrc``: :func:`configured_bus`), else :data:`DEFAULT_CAN_INTERFACE` (and
    :data:`DEFAULT_CAN_BITRATE`); ``fd`` enables CAN FD; ``bitrate`` and ``data_bitrate``
    (bits/s) configure adapters that take them and set the wire budget (SocketCAN takes its
    bitrate from ``ip link``; vcan has none, so the budget is all that paces it);
    ``bus_kwargs`` are further ``can.Bus`` keyword arguments for vendor adapters
    (:func:`parse_bus_kwargs`). A reader thread drains the bus continuously, so the kernel's
    socket buffer never overflows silently; ``rx_overflows`` counts frames the thread
    had to discard.
    """

    kind = "can"
    scheme = "can"
    carries_frames = True
    unit = "frames"

    def __init__(self, channel: str, interface: str | None = None, fd: bool = False,
                 bitrate: int | None = None, data_bitrate: int | None = None,
                 bus_kwargs: Mapping[str, Any] | None = None) -> None:
        import can

        configured = configured_bus(channel) if interface is None or bitrate is None else {}
        from_config = interface is None and "interface" in configured
        if interface is None:
            interface = str(configured.get("interface", DEFAULT_CAN_INTERFACE))
        if bitrate is None:
            bitrate = int(configured.get("bitrate") or DEFAULT_CAN_BITRATE)
        self.channel = channel
        self.interface = interface
        self.fd = bool(fd)
        self.can_fd = self.fd
        self.bitrate = check_bitrate(bitrate)
        try:
            self.bus_kwargs = _checked_bus_kwargs(bus_kwargs or {})
        except ValueError as exc:
            raise TransportError(str(exc)) from None
        """Further ``can.Bus`` keyword arguments (vendor adapters' own settings)."""
        self.data_bitrate = None if data_bitrate is None else check_bitrate(
            data_bitrate, "data bitrate")
        if self.data_bitrate is not None and not self.fd:
            raise TransportError("a CAN data bitrate needs CAN FD: add --fd or drop "
                                 "--data-bitrate")
        kwargs: dict[str, Any] = {"channel": channel, "interface": interface, "fd": self.fd,
                                  "bitrate": self.bitrate}
        if self.data_bitrate is not None:
            kwargs["data_bitrate"] = self.data_bitrate
        kwargs.update(self.bus_kwargs)
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
            where = (" (named by python-can's configuration: CAN_INTERFACE or ~/.canrc)"
                     if from_config else "")
            raise TransportError(f"CAN interface {interface!r}{where} is not available: {exc};"
                                 " see python-can's list of interfaces (socketcan, virtual, "
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
        self.rcvbuf_asked = CAN_RCVBUF_BYTES if isinstance(sock, socket.socket) else 0
        """Receive buffer asked of the kernel (bytes; 0: the interface has no socket)."""
        self.rcvbuf_granted = request_receive_buffer(
            sock, CAN_RCVBUF_BYTES, f"CAN {channel}") if isinstance(sock, socket.socket) else 0
        """Receive buffer the kernel granted (bytes): below :attr:`rcvbuf_asked` a warning
        names the setting (``net.core.rmem_max``) to raise."""
        self.rx_overflows = 0
        self._rx: collections.deque[Any] = collections.deque()
        self._rx_ready = threading.Condition()
        self._rx_error: Exception | None = None
        self._closed = threading.Event()
        self._reader = threading.Thread(target=self._read_loop, name=f"can-rx-{channel}",
                                        daemon=True)
        self._reader.start()

    @classmethod
    def url_can_fd(cls, url: LinkUrl) -> bool:
        return url.bool_option("fd")

    @classmethod
    def from_url(cls, url: LinkUrl, role: Role) -> CanTransport:
        """``can:CHANNEL?interface=NAME&fd=1&bitrate=N&data_bitrate=N&bus_kwargs=K=V,...``;
        either role. Without ``interface`` (``bitrate``) python-can's configuration gives it
        (:func:`configured_bus`)."""
        url.check_options(("interface", "fd", "bitrate", "data_bitrate", "bus_kwargs"))
        try:
            bus_kwargs = parse_bus_kwargs(url.options.get("bus_kwargs", ""))
        except ValueError as exc:
            raise TransportError(f"link URL {url}: {exc}") from None
        return cls(url.require_target("can:vcan0?fd=1"), url.options.get("interface"),
                   fd=cls.url_can_fd(url), bitrate=url.int_option("bitrate", None),
                   data_bitrate=url.int_option("data_bitrate", None), bus_kwargs=bus_kwargs)

    @property
    def name(self) -> str:
        return f"{self.interface}:{self.channel}"

    @property
    def url(self) -> str:
        return format_url("can", self.channel, interface=self.interface, fd=self.fd,
                          bitrate=self.bitrate, data_bitrate=self.data_bitrate,
                          bus_kwargs=format_bus_kwargs(self.bus_kwargs) or None)

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
        deadline = Deadline(timeout)
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
        deadline = Deadline(timeout)
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


def configured_bus(channel: str) -> dict[str, Any]:
    """python-can's own configuration for ``channel``, as ``can.Bus(channel=...)`` reads it
    (``can.util.load_config``'s sources, first wins): ``can.rc``, the environment
    (``CAN_INTERFACE``, ``CAN_BITRATE``, ...) and its files (``~/.canrc``, ``~/.can``,
    ``/etc/can.conf``); the legacy ``bustype`` read as ``interface``. No ``interface`` key
    when none names one; an unknown one is refused by ``can.Bus`` when the link opens."""
    import can
    import can.util

    out: dict[str, Any] = {}
    for source in (can.rc, can.util.load_environment_config(),
                   can.util.load_file_config()):
        config = dict(source)
        if "bustype" in config and not config.get("interface"):
            config["interface"] = config.pop("bustype")
        for key, value in config.items():
            if key not in out and value not in (None, ""):
                out[key] = can.util.cast_from_string(value) if isinstance(value, str) else value
    return out


def parse_bus_kwargs(text: str) -> dict[str, Any]:
    """Extra ``can.Bus`` keyword arguments from ``KEY=VALUE,KEY=VALUE`` (each value read as
    python-can reads its configuration files: integers, floats, booleans, else text) or from
    a JSON object; empty text gives none. :class:`ValueError` saying what to write when the
    text is neither, or names an argument the link sets itself (:data:`OWN_BUS_KEYS`)."""
    from can.util import cast_from_string

    text = text.strip()
    if not text:
        return {}
    if text.startswith("{"):
        try:
            parsed = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"bus keyword arguments {text!r} are not a JSON object ({exc.msg}):"
                             " give KEY=VALUE,... or {\"KEY\": VALUE}") from None
        if not isinstance(parsed, dict):
            raise ValueError(f"bus keyword arguments {text!r} are not a JSON object: give "
                             "KEY=VALUE,... or {\"KEY\": VALUE}")
        return _checked_bus_kwargs(parsed)
    out: dict[str, Any] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key.isidentifier():
            raise ValueError(f"bus keyword argument {item!r} is not KEY=VALUE: give e.g. "
                             "sjw_abr=8,tseg1_abr=31")
        out[key] = cast_from_string(value.strip())
    return _checked_bus_kwargs(out)


def format_bus_kwargs(kwargs: Mapping[str, Any]) -> str:
    """``kwargs`` as :func:`parse_bus_kwargs` reads them back (JSON; empty when none)."""
    return json.dumps(dict(kwargs), separators=(",", ":")) if kwargs else ""


def _checked_bus_kwargs(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    for key in kwargs:
        if key in OWN_BUS_KEYS:
            raise ValueError(f"bus keyword argument {key!r} is one skinhil sets: give it as "
                             f"--{key.replace('_', '-')} (or {key}= in the link URL)")
    return dict(kwargs)


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
