"""The one interface every link implements: :class:`Transport`, and what its plugins share.

Modelled on python-can's ``BusABC``: :meth:`Transport.send`, :meth:`Transport.recv`,
:meth:`Transport.shutdown`, usable as a context manager. Timeouts are uniform, in seconds:
``None`` blocks, ``0`` polls (never blocks), ``> 0`` is a deadline on the monotonic clock
(:class:`Deadline`).

A serial link carries ``bytes``; a CAN link carries ``list[protocols.CanFrame]``. Both say
how long a payload occupies the real wire (:meth:`Transport.wire_seconds`), so a sender can
pace a pty or a vcan, which have no bit timing, to the baud rate or bitrate it emulates.

Transports know nothing about the board: the board and the receiver both use them. Errors
on open and on a link that goes away are :class:`skinhil.errors.TransportError` with a
one-line message saying what to do.
"""

from __future__ import annotations

import abc
import errno
import os
import select
import time
from typing import TYPE_CHECKING, Any, Generic, Literal, TypeVar

from skinhil.errors import TransportError

if TYPE_CHECKING:
    from skinhil.transports.url import LinkUrl

P = TypeVar("P")

Role = Literal["board", "host"]
"""Which end opens a link: the board sends to the address, the host listens on it."""

DEFAULT_BAUD = 921600
"""Default serial baud rate (bits/s): every serial link and option defaults to it."""
MIN_BAUD = 50
"""Smallest baud rate accepted (bits/s)."""
MAX_BAUD = 20_000_000
"""Largest baud rate accepted (bits/s)."""
MAX_CAN_BITRATE = 12_000_000
"""Largest CAN (FD data phase) bitrate accepted (bits/s)."""


class Transport(abc.ABC, Generic[P]):
    """A link that moves payloads of type ``P`` (``bytes`` or ``list[CanFrame]``)."""

    kind: str = "abstract"
    """The wire family a recording of this link names: "serial", "can" or "udp"."""
    scheme: str = ""
    """The URL scheme this class opens (:mod:`skinhil.transports.registry`)."""
    carries_frames: bool = False
    """True: payloads are ``list[protocols.CanFrame]``; False: ``bytes``."""
    can_fd: bool = False
    """True on a CAN FD link (64-byte frames)."""
    whole_datagrams: bool = False
    """True when every send must hold whole packets (a datagram link, SPEC.md §10)."""

    unit: str = "bytes"
    """The name of this link's unit of payload: "bytes", or "frames" on a frames link."""

    @property
    def url(self) -> str:
        """The URL that opens this link again (:func:`skinhil.transports.open_link`)."""
        return self.name

    @classmethod
    def url_can_fd(cls, url: LinkUrl) -> bool:
        """Whether the link ``url`` names is CAN FD, known before it is opened."""
        return False

    @classmethod
    def from_url(cls, url: LinkUrl, role: Role) -> Transport[Any]:
        """Open the link ``url`` names, for ``role`` ("board" sends, "host" listens)."""
        raise TransportError(f"the {cls.__name__} link does not open URLs: give a link of "
                             "one of the schemes skinhil.transports.link_schemes() lists")

    def codec_pair(self, board_id: int = 0, step_us: int = 100,
                   n_channels: int | None = None, fd: bool | None = None) -> tuple[Any, Any]:
        """A fresh (encoder, decoder) of the protocols codecs that fit this link: the CAN
        layout of board ``board_id`` (CAN FD when ``fd``, default :attr:`can_fd`) on a
        frames link, the serial framing on a bytes link; ``step_us`` is the timestamp
        resolution (µs), ``n_channels`` the board's channel count (default: the paper's)."""
        import protocols

        channels = protocols.N_CHANNELS if n_channels is None else n_channels
        if self.carries_frames:
            layout = self.can_fd if fd is None else fd
            return (protocols.CanEncoder(board_id=board_id, fd=layout, step_us=step_us,
                                         n_channels=channels),
                    protocols.CanDecoder(board_id=board_id, fd=layout))
        return (protocols.SerialEncoder(step_us=step_us, n_channels=channels),
                protocols.SerialDecoder())

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


class WrappedTransport(Transport[P]):
    """A transport around another (``inner``): everything goes to ``inner`` unless a
    subclass changes it (faults injected, units recorded)."""

    def __init__(self, inner: Transport[P]) -> None:
        self.inner = inner
        self.kind = inner.kind
        self.scheme = inner.scheme
        self.carries_frames = inner.carries_frames
        self.can_fd = inner.can_fd
        self.whole_datagrams = inner.whole_datagrams
        self.unit = inner.unit

    @property
    def name(self) -> str:
        return self.inner.name

    @property
    def url(self) -> str:
        return self.inner.url

    def codec_pair(self, board_id: int = 0, step_us: int = 100,
                   n_channels: int | None = None, fd: bool | None = None) -> tuple[Any, Any]:
        return self.inner.codec_pair(board_id, step_us, n_channels, fd)

    def send(self, payload: P, timeout: float | None = None) -> int:
        return self.inner.send(payload, timeout)

    def recv(self, timeout: float | None = None) -> P:
        return self.inner.recv(timeout)

    def wire_seconds(self, payload: P) -> float:
        return self.inner.wire_seconds(payload)

    def empty(self) -> P:
        return self.inner.empty()

    def shutdown(self) -> None:
        self.inner.shutdown()


class Deadline:
    """A timeout in seconds turned into a monotonic deadline (None: no deadline)."""

    def __init__(self, timeout: float | None) -> None:
        if timeout is not None and timeout < 0:
            raise ValueError(f"timeout must be None or >= 0 seconds, got {timeout!r}")
        self.end = None if timeout is None else time.monotonic() + timeout

    def left(self) -> float | None:
        return None if self.end is None else max(0.0, self.end - time.monotonic())


def check_baud(baud: int) -> int:
    """``baud`` if it is a usable baud rate (bits/s), else :class:`TransportError`."""
    if not isinstance(baud, int) or isinstance(baud, bool) or not MIN_BAUD <= baud <= MAX_BAUD:
        raise TransportError(f"invalid baud rate {baud!r}: give an integer from {MIN_BAUD} to "
                             f"{MAX_BAUD} bits/s, e.g. --baud {DEFAULT_BAUD}")
    return baud


def check_bitrate(bitrate: int, what: str = "bitrate") -> int:
    """``bitrate`` if it is a usable CAN bitrate (bits/s), else :class:`TransportError`."""
    if (not isinstance(bitrate, int) or isinstance(bitrate, bool)
            or not 1000 <= bitrate <= MAX_CAN_BITRATE):
        raise TransportError(f"invalid CAN {what} {bitrate!r}: give an integer from 1000 to "
                             f"{MAX_CAN_BITRATE} bits/s, e.g. 1000000")
    return bitrate


READ_CHUNK = 65536
"""Bytes one :func:`read_fd` takes at most."""


def read_fd(fd: int, timeout: float | None) -> bytes:
    """What a non-blocking fd holds (at most :data:`READ_CHUNK` bytes), waiting at most
    ``timeout`` s (None: for ever) for the first byte; b"" when nothing came. An fd that
    reports data and gives none has lost its other end: :class:`OSError`."""
    ready, _, _ = select.select([fd], [], [], timeout)
    if not ready:
        return b""
    try:
        data = os.read(fd, READ_CHUNK)
    except BlockingIOError:
        return b""
    if not data:
        raise OSError(errno.EIO, "the device reports data and gives none (disconnected?)")
    return data


def write_fd(fd: int, payload: bytes, deadline: Deadline) -> int:
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
