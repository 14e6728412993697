"""The links the board and the receiver talk over, behind one interface.

:class:`Transport` (like python-can's ``BusABC``: send / recv / shutdown, uniform timeouts in
seconds: None blocks, 0 polls, > 0 a monotonic deadline) and its plugins:

- :class:`SerialTransport`: pyserial, a device path or a URL (``loop://``, ``socket://``);
- :class:`CanTransport`: python-can's ``can.Bus``, classic CAN or CAN FD, any interface;
- :class:`PtyMasterTransport`: the master end of a pty pair (the slave is a serial port);
- :class:`FaultyTransport`: seeded drops, corruption, duplicates and delays around any of them;
- :class:`UdpTransport`: the serial packet stream in UDP datagrams (whole packets in each).

Each link class opens its own URL scheme (``serial:``, ``can:``, ``udp:``, ``pty:``), found
by :func:`open_link` in the ``skinhil.links`` entry points or added by :func:`register_link`
(:mod:`skinhil.transports.registry`, docs/links.md).
"""

from skinhil.transports.base import (
    DEFAULT_BAUD,
    Deadline,
    Role,
    Transport,
    check_baud,
    check_bitrate,
)
from skinhil.transports.can import CanTransport
from skinhil.transports.faults import FaultParams, FaultyTransport, InjectedFaults
from skinhil.transports.pty import PtyMasterTransport
from skinhil.transports.registry import link_class, link_schemes, open_link, register_link
from skinhil.transports.serial import SerialTransport
from skinhil.transports.udp import UdpTransport
from skinhil.transports.url import LinkUrl, format_url

__all__ = [
    "DEFAULT_BAUD",
    "LinkUrl",
    "Role",
    "format_url",
    "link_class",
    "link_schemes",
    "open_link",
    "register_link",
    "CanTransport",
    "Deadline",
    "FaultParams",
    "FaultyTransport",
    "InjectedFaults",
    "PtyMasterTransport",
    "SerialTransport",
    "Transport",
    "UdpTransport",
    "check_baud",
    "check_bitrate",
]
