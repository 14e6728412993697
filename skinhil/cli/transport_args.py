"""Transport options shared by the subcommands that talk over a link (serve, listen).

Exactly one of ``--port PORT`` (serial: a device path or a pyserial URL, with ``--baud``),
``--can CHANNEL`` (python-can, with ``--interface``, ``--fd``, ``--bitrate``,
``--data-bitrate``) or ``--udp [HOST:]PORT`` (the serial packets in UDP datagrams, with
``--bitrate``: the board sends to HOST:PORT, the host listens on it) selects the link;
:func:`open_transport` opens it.
"""

from __future__ import annotations

import argparse

from skinhil.cli.values import integer
from skinhil.errors import ConfigError
from skinhil.transports import CanTransport, SerialTransport, Transport, UdpTransport
from skinhil.transports.base import MAX_BAUD, MIN_BAUD
from skinhil.transports.udp import DEFAULT_UDP_BITRATE, parse_address

DEFAULT_BAUD = 921600
"""Default serial baud rate (bits/s)."""
DEFAULT_BITRATE = 1_000_000
"""Default CAN (arbitration phase) bitrate (bits/s)."""
UDP_LISTEN_HOST = "127.0.0.1"
"""Address a host listens on when ``--udp`` gives only a port (0.0.0.0: every interface)."""


MAX_BITRATE = 100_000_000
"""Highest baud rate or bitrate (bits/s) an option takes; each link checks its own."""
baud_value = integer(MIN_BAUD, MAX_BAUD, "baud rate")
"""argparse type: a serial baud rate (bits/s), the range the serial transport takes."""
bitrate_value = integer(1, MAX_BITRATE, "bitrate")
"""argparse type: a CAN or UDP bitrate (bits/s)."""


def add_transport_args(parser: argparse.ArgumentParser, udp_listen: bool = False,
                       required: bool = True, title: str = "link (one of --port, --can or --udp)"
                       ) -> None:
    """Add the link options to ``parser`` (one of --port, --can or --udp; required unless
    ``required`` is false, under the group heading ``title``).

    ``udp_listen``: this end listens on the ``--udp`` address (the host) instead of sending
    to it (the board).
    """
    group = parser.add_argument_group(title)
    parser.set_defaults(udp_listen=udp_listen)
    which = group.add_mutually_exclusive_group(required=required)
    which.add_argument("--port", metavar="PORT",
                       help="serial port: device path (/dev/ttyUSB0, /dev/pts/3) or pyserial "
                            "URL (loop://, socket://host:port)")
    which.add_argument("--can", metavar="CHANNEL",
                       help="CAN channel, e.g. can0 or vcan0 (python-can)")
    if udp_listen:
        which.add_argument("--udp", metavar="[HOST:]PORT",
                           help="listen for boards on this UDP port (host default "
                                f"{UDP_LISTEN_HOST}; 0.0.0.0:PORT hears other machines)")
    else:
        which.add_argument("--udp", metavar="HOST:PORT",
                           help="send the serial packet stream in UDP datagrams to HOST:PORT")
    group.add_argument("--baud", type=baud_value, default=DEFAULT_BAUD, metavar="N",
                       help=f"serial baud rate, bits/s, 8N1, {MIN_BAUD}..{MAX_BAUD} (default: "
                            f"{DEFAULT_BAUD})")
    group.add_argument("--interface", default="socketcan", metavar="NAME",
                       help="python-can interface: socketcan, virtual, pcan, kvaser, slcan, "
                            "udp_multicast, ... (default: socketcan)")
    group.add_argument("--fd", action="store_true", help="use CAN FD (64-byte frames)")
    group.add_argument("--bitrate", type=bitrate_value, default=None, metavar="N",
                       help=f"CAN (arbitration) bitrate, bits/s (default: {DEFAULT_BITRATE}); "
                            f"UDP wire budget (default: {DEFAULT_UDP_BITRATE})")
    group.add_argument("--data-bitrate", type=bitrate_value, default=None, metavar="N",
                       help="CAN FD data-phase bitrate, bits/s (default: same as --bitrate)")


def check_transport_args(args: argparse.Namespace) -> None:
    """:class:`ConfigError` when :func:`add_transport_args`' options do not fit together."""
    if args.port is not None or args.udp is not None:
        if args.fd or args.data_bitrate is not None:
            raise ConfigError("--fd and --data-bitrate are CAN options; use them with --can")
    if args.port is not None and args.bitrate is not None:
        raise ConfigError("--bitrate is the rate of a CAN or UDP link; a serial port's "
                          "is --baud")


def transport_argv(args: argparse.Namespace) -> list[str]:
    """The link options of ``args`` as a command line gives them (for a ``skinhil serve``
    another command starts on the same link); empty when no link is selected."""
    if args.port is not None:
        return ["--port", args.port, "--baud", str(args.baud)]
    if args.udp is not None:
        return ["--udp", args.udp, *(["--bitrate", str(args.bitrate)] if args.bitrate else [])]
    if args.can is None:
        return []
    return ["--can", args.can, "--interface", args.interface, *(["--fd"] if args.fd else []),
            *(["--bitrate", str(args.bitrate)] if args.bitrate is not None else []),
            *(["--data-bitrate", str(args.data_bitrate)] if args.data_bitrate is not None
              else [])]


def open_transport(args: argparse.Namespace) -> Transport[bytes] | Transport[list]:
    """Open the link selected by :func:`add_transport_args`' options.

    Raises :class:`skinhil.errors.TransportError` (port or channel unusable) or
    :class:`ConfigError` (options that do not fit together).
    """
    check_transport_args(args)
    if args.port is not None:
        return SerialTransport(args.port, args.baud)
    if args.udp is not None:
        host, port = parse_address(args.udp, UDP_LISTEN_HOST if args.udp_listen else None)
        return UdpTransport(host, port, listen=args.udp_listen,
                            bitrate=_or(args.bitrate, DEFAULT_UDP_BITRATE))
    if args.can is None:
        raise ConfigError("give a link: --port PORT (serial), --can CHANNEL (CAN) or "
                          "--udp HOST:PORT (UDP)")
    return CanTransport(args.can, args.interface, fd=args.fd,
                        bitrate=_or(args.bitrate, DEFAULT_BITRATE), data_bitrate=args.data_bitrate)


def describe_transport(args: argparse.Namespace) -> str:
    """A short description of the selected link, for status lines."""
    if args.port is not None:
        return f"serial {args.port} @ {args.baud} baud"
    if args.udp is not None:
        return (f"UDP {'listening on' if args.udp_listen else 'to'} {args.udp} @ "
                f"{_or(args.bitrate, DEFAULT_UDP_BITRATE)} bit/s")
    rate = f"{_or(args.bitrate, DEFAULT_BITRATE)} bit/s" + (f", data {args.data_bitrate} bit/s"
                                      if args.data_bitrate else "")
    return f"CAN{' FD' if args.fd else ''} {args.interface}:{args.can} @ {rate}"


def _or(value: int | None, default: int) -> int:
    """``value``, or ``default`` when the option was not given (0 is not "not given")."""
    return default if value is None else value
