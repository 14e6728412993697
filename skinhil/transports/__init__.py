"""The links the board and the receiver talk over, behind one interface.

:class:`Transport` (like python-can's ``BusABC``: send / recv / shutdown, uniform timeouts in
seconds: None blocks, 0 polls, > 0 a monotonic deadline) and its plugins:

- :class:`SerialTransport`: pyserial, a device path or a URL (``loop://``, ``socket://``);
- :class:`CanTransport`: python-can's ``can.Bus``, classic CAN or CAN FD, any interface;
- :class:`PtyMasterTransport`: the master end of a pty pair (the slave is a serial port);
- :class:`FaultyTransport`: seeded drops, corruption, duplicates and delays around any of them;
- :class:`UdpTransport`: the serial packet stream in UDP datagrams (whole packets in each).
"""

from skinhil.transports.base import Deadline, Transport, check_baud, check_bitrate
from skinhil.transports.can import CanTransport
from skinhil.transports.faults import FaultParams, FaultyTransport, InjectedFaults
from skinhil.transports.pty import PtyMasterTransport
from skinhil.transports.serial import SerialTransport
from skinhil.transports.udp import UdpTransport

__all__ = [
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
