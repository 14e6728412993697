"""UDP links: the serial packet stream in datagrams, for event rates no UART or CAN bus carries.

The payload is ``bytes`` of the serial packet format (SPEC.md §2-§4, §10): a sender puts one
or more whole packets in each datagram, so a lost datagram loses whole packets, which the
sequence numbers count, and the receiver's loss accounting stays exact. The board end
connects to the host's ``HOST:PORT``; the host end binds ``HOST:PORT`` and hears any number of
boards, each a source address (:meth:`UdpTransport.recv_from` keeps them apart; commands go
to the source heard last).

There is no bit timing to emulate: ``bitrate`` (bits/s, default 100 Mbit/s) only sets the
wire budget a sender paces itself to, counting payload bytes (8 bits each; IP and UDP headers
are not counted).

As a link URL: ``udp:HOST:PORT?bitrate=N`` (the board sends to it, the host listens on it;
a host may give ``udp:PORT``, listening on :data:`UDP_LISTEN_HOST`), docs/links.md.
"""

from __future__ import annotations

import errno
import logging
import select
import socket

from skinhil.errors import TransportError
from skinhil.transports.base import Deadline, Role, Transport
from skinhil.transports.socket_buffer import request_receive_buffer
from skinhil.transports.url import LinkUrl, format_url

log = logging.getLogger(__name__)

DEFAULT_UDP_BITRATE = 100_000_000
"""Default wire budget of a UDP link (bits/s of payload): Fast Ethernet."""
UDP_LISTEN_HOST = "127.0.0.1"
"""Address a host listens on when a UDP URL gives only a port (0.0.0.0: every interface)."""
MAX_UDP_BITRATE = 10_000_000_000
"""Largest UDP wire budget accepted (bits/s)."""
MAX_DATAGRAM_BYTES = 1472
"""Largest datagram sent (bytes): an Ethernet frame's 1500-byte MTU less the IPv4 and UDP
headers, so no datagram is fragmented; a serial packet (at most 1032 bytes) always fits."""
UDP_RCVBUF_BYTES = 8 * 1024 * 1024
"""Socket receive buffer requested (the kernel may cap it: net.core.rmem_max)."""
RECV_BATCH = 4096
"""Most datagrams one :meth:`UdpTransport.recv_from` call takes from the socket."""


def parse_address(text: str, default_host: str | None) -> tuple[str, int]:
    """``(host, port)`` from ``HOST:PORT`` (or ``PORT`` alone when ``default_host`` is given).

    Raises :class:`TransportError` with what to write instead.
    """
    host, sep, port_text = text.rpartition(":")
    if not sep:
        host = default_host or ""
    if not host:
        raise TransportError(f"UDP address {text!r} needs a host: write HOST:PORT, e.g. "
                             "127.0.0.1:5005")
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        raise TransportError(f"UDP address {text!r}: the port must be an integer 0..65535, "
                             "e.g. 127.0.0.1:5005")
    return host.strip("[]"), port


def split_packets(payload: bytes, limit: int) -> list[bytes]:
    """``payload`` cut into datagrams of at most ``limit`` bytes, each ending after a 0x00
    packet delimiter where one lies within the limit (whole packets per datagram)."""
    out = []
    start = 0
    n = len(payload)
    while start < n:
        end = min(n, start + limit)
        if end < n:
            cut = payload.rfind(0, start, end)
            if cut >= start:
                end = cut + 1
        out.append(payload[start:end])
        start = end
    return out


class UdpTransport(Transport[bytes]):
    """A UDP socket: ``listen=False`` sends to ``host:port`` (the board), ``listen=True``
    binds ``host:port`` (the host; port 0 picks a free one, see :attr:`port`).

    ``bitrate`` (bits/s) is the wire budget; ``max_datagram`` (bytes) the largest datagram;
    ``rcvbuf_bytes`` the receive buffer asked of the kernel (see :attr:`rcvbuf_granted`).
    """

    kind = "udp"
    scheme = "udp"
    whole_datagrams = True

    def __init__(self, host: str, port: int, listen: bool = False,
                 bitrate: int = DEFAULT_UDP_BITRATE,
                 max_datagram: int = MAX_DATAGRAM_BYTES,
                 rcvbuf_bytes: int = UDP_RCVBUF_BYTES) -> None:
        if (not isinstance(bitrate, int) or isinstance(bitrate, bool)
                or not 1000 <= bitrate <= MAX_UDP_BITRATE):
            raise TransportError(f"invalid UDP bitrate {bitrate!r}: give an integer from 1000 "
                                 f"to {MAX_UDP_BITRATE} bits/s, e.g. 100000000")
        if not 64 <= max_datagram <= 65507:
            raise TransportError(f"UDP datagram limit {max_datagram} bytes is outside 64..65507")
        self.bitrate = bitrate
        self.listen = listen
        self.host = host
        self.max_datagram = max_datagram
        self.refused = 0
        """Datagrams the network refused (nobody listening at the destination yet): lost."""
        self.peer: tuple[str, int] | None = None
        """Where :meth:`send` goes: the destination, or (listening) the source heard last."""
        self._closed = False
        try:
            infos = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
        except (socket.gaierror, UnicodeError) as exc:
            raise TransportError(f"unknown UDP host {host!r}: {exc}; give an IP address such "
                                 "as 127.0.0.1 or a resolvable name") from None
        family, _, _, _, addr = infos[0]
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        self.rcvbuf_asked = int(rcvbuf_bytes) if listen else 0
        """Receive buffer asked of the kernel (bytes; a receiver's only: 0 when sending)."""
        self.rcvbuf_granted = request_receive_buffer(
            self._sock, self.rcvbuf_asked, f"UDP {host}:{port}") if listen else 0
        """Receive buffer the kernel granted (bytes): below :attr:`rcvbuf_asked` a warning
        names the setting (``net.core.rmem_max``) to raise."""
        try:
            if listen:
                self._sock.bind(addr)
            else:
                self._sock.connect(addr)
                self.peer = (str(addr[0]), int(addr[1]))
        except OSError as exc:
            self._sock.close()
            what = "bind" if listen else "send to"
            hint = " (another program uses the port: choose another)" \
                if exc.errno == errno.EADDRINUSE else ""
            raise TransportError(f"cannot {what} UDP {host}:{port}: {exc.strerror or exc}"
                                 f"{hint}") from None
        self._sock.setblocking(False)
        local = self._sock.getsockname()
        self.port = int(local[1])
        """The local port (the bound one when listening)."""
        self._name = f"udp:{host}:{self.port if listen else port}"

    @classmethod
    def from_url(cls, url: LinkUrl, role: Role) -> UdpTransport:
        """``udp:HOST:PORT?bitrate=N``: role "board" sends to it, "host" listens on it
        (``udp:PORT`` listens on :data:`UDP_LISTEN_HOST`)."""
        url.check_options(("bitrate",))
        listen = role == "host"
        host, port = parse_address(url.require_target("udp:127.0.0.1:9000"),
                                   UDP_LISTEN_HOST if listen else None)
        bitrate = url.int_option("bitrate", DEFAULT_UDP_BITRATE)
        return cls(host, port, listen=listen,
                   bitrate=DEFAULT_UDP_BITRATE if bitrate is None else bitrate)

    @property
    def name(self) -> str:
        return self._name

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        port = self.port if self.listen else (self.peer[1] if self.peer else self.port)
        return format_url("udp", f"{host}:{port}", bitrate=self.bitrate)

    def _check_open(self) -> None:
        if self._closed:
            raise TransportError(f"UDP link {self._name} is closed")

    def send(self, payload: bytes, timeout: float | None = None) -> int:
        """Send ``payload`` in datagrams of whole packets; return the bytes accepted (whole
        datagrams: what does not go by the deadline is left to the caller)."""
        self._check_open()
        if not payload:
            return 0
        if self.peer is None:
            log.debug("no UDP peer yet on %s: %d bytes not sent", self._name, len(payload))
            return 0
        deadline = Deadline(timeout)
        sent = 0
        for datagram in split_packets(bytes(payload), self.max_datagram):
            while True:
                try:
                    if self.listen:
                        self._sock.sendto(datagram, self.peer)
                    else:
                        self._sock.send(datagram)
                    break
                except (BlockingIOError, InterruptedError):
                    left = deadline.left()
                    if left == 0.0:
                        return sent
                    select.select([], [self._sock], [], left)
                except ConnectionRefusedError:
                    self.refused += 1  # nobody listens yet: this datagram is lost
                    break
                except OSError as exc:
                    raise TransportError(f"UDP link {self._name} failed: {exc}") from None
            sent += len(datagram)
        return sent

    def recv_from(self, timeout: float | None = None) -> list[tuple[str, bytes]]:
        """Datagrams received by the deadline, each with its source as ``"host:port"``."""
        self._check_open()
        deadline = Deadline(timeout)
        out: list[tuple[str, bytes]] = []
        while len(out) < RECV_BATCH:
            try:
                data, src = self._sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                if out:
                    break
                left = deadline.left()
                if left == 0.0 or self._closed:
                    break
                ready, _, _ = select.select([self._sock], [], [], left)
                if not ready:
                    break
                continue
            except ConnectionRefusedError:
                self.refused += 1
                continue
            except OSError as exc:
                if self._closed:
                    break
                raise TransportError(f"UDP link {self._name} failed: {exc}") from None
            if self.listen:
                self.peer = (src[0], src[1])
            out.append((f"{src[0]}:{src[1]}", data))
        return out

    def recv(self, timeout: float | None = None) -> bytes:
        return b"".join(data for _, data in self.recv_from(timeout))

    def wire_seconds(self, payload: bytes) -> float:
        return 8 * len(payload) / self.bitrate

    def empty(self) -> bytes:
        return b""

    def shutdown(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._sock.close()
