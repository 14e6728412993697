"""Transport options shared by the subcommands that talk over a link (serve, listen).

Exactly one of ``--port PORT`` (serial: a device path or a pyserial URL, with ``--baud``) or
``--can CHANNEL`` (python-can, with ``--interface``, ``--fd``, ``--bitrate``,
``--data-bitrate``) selects the link; :func:`open_transport` opens it.
"""

from __future__ import annotations

import argparse

from skinhil.errors import ConfigError
from skinhil.transports import CanTransport, SerialTransport, Transport

DEFAULT_BAUD = 921600
"""Default serial baud rate (bits/s)."""
DEFAULT_BITRATE = 1_000_000
"""Default CAN (arbitration phase) bitrate (bits/s)."""


def _int_value(text: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None


def add_transport_args(parser: argparse.ArgumentParser) -> None:
    """Add the serial/CAN link options to ``parser`` (one of --port or --can is required)."""
    group = parser.add_argument_group("link (one of --port or --can)")
    which = group.add_mutually_exclusive_group(required=True)
    which.add_argument("--port", metavar="PORT",
                       help="serial port: device path (/dev/ttyUSB0, /dev/pts/3) or pyserial "
                            "URL (loop://, socket://host:port)")
    which.add_argument("--can", metavar="CHANNEL",
                       help="CAN channel, e.g. can0 or vcan0 (python-can)")
    group.add_argument("--baud", type=_int_value, default=DEFAULT_BAUD, metavar="N",
                       help=f"serial baud rate, bits/s, 8N1 (default: {DEFAULT_BAUD})")
    group.add_argument("--interface", default="socketcan", metavar="NAME",
                       help="python-can interface: socketcan, virtual, pcan, kvaser, slcan, "
                            "udp_multicast, ... (default: socketcan)")
    group.add_argument("--fd", action="store_true", help="use CAN FD (64-byte frames)")
    group.add_argument("--bitrate", type=_int_value, default=DEFAULT_BITRATE, metavar="N",
                       help=f"CAN (arbitration) bitrate, bits/s (default: {DEFAULT_BITRATE})")
    group.add_argument("--data-bitrate", type=_int_value, default=None, metavar="N",
                       help="CAN FD data-phase bitrate, bits/s (default: same as --bitrate)")


def open_transport(args: argparse.Namespace) -> Transport[bytes] | Transport[list]:
    """Open the link selected by :func:`add_transport_args`' options.

    Raises :class:`skinhil.errors.TransportError` (port or channel unusable) or
    :class:`ConfigError` (options that do not fit together).
    """
    if args.port is not None:
        if args.fd or args.data_bitrate is not None:
            raise ConfigError("--fd and --data-bitrate are CAN options; use them with --can")
        return SerialTransport(args.port, args.baud)
    if args.can is None:
        raise ConfigError("give a link: --port PORT (serial) or --can CHANNEL (CAN)")
    return CanTransport(args.can, args.interface, fd=args.fd, bitrate=args.bitrate,
                        data_bitrate=args.data_bitrate)


def describe_transport(args: argparse.Namespace) -> str:
    """A short description of the selected link, for status lines."""
    if args.port is not None:
        return f"serial {args.port} @ {args.baud} baud"
    rate = f"{args.bitrate} bit/s" + (f", data {args.data_bitrate} bit/s"
                                      if args.data_bitrate else "")
    return f"CAN{' FD' if args.fd else ''} {args.interface}:{args.can} @ {rate}"
