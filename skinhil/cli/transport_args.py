"""Link options shared by the subcommands that talk over a link (serve, listen, bench).

``--link URL`` selects any registered link (docs: Links: ``serial:``, ``can:``, ``udp:``,
``pty:`` and the schemes packages add). The shorthands build that URL: ``--port PORT``
(serial: a device path or a pyserial URL, with ``--baud``), ``--can CHANNEL`` (python-can,
with ``--interface``, ``--fd``, ``--bitrate``, ``--data-bitrate``, ``--bus-kwargs``; without
``--interface`` python-can's own configuration, ``CAN_INTERFACE`` or ``~/.canrc``, names it)
and ``--udp [HOST:]PORT`` (the serial packets in UDP datagrams, with ``--bitrate``: the board
sends to HOST:PORT, the host listens on it). :func:`link_url` is the one place they become a URL;
:func:`open_transport` opens it.
"""

from __future__ import annotations

import argparse
from typing import Any

from skinhil.cli.values import integer
from skinhil.errors import ConfigError
from skinhil.transports import (
    DEFAULT_BAUD,
    LinkUrl,
    Role,
    Transport,
    format_url,
    link_class,
    open_link,
)
from skinhil.transports.base import MAX_BAUD, MIN_BAUD
from skinhil.transports.can import (
    DEFAULT_CAN_BITRATE,
    DEFAULT_CAN_INTERFACE,
    format_bus_kwargs,
    parse_bus_kwargs,
)
from skinhil.transports.udp import DEFAULT_UDP_BITRATE, UDP_LISTEN_HOST

MAX_BITRATE = 100_000_000
"""Highest baud rate or bitrate (bits/s) an option takes; each link checks its own."""
baud_value = integer(MIN_BAUD, MAX_BAUD, "baud rate")
"""argparse type: a serial baud rate (bits/s), the range the serial transport takes."""
bitrate_value = integer(1, MAX_BITRATE, "bitrate")
"""argparse type: a CAN or UDP bitrate (bits/s)."""
SHORTHAND_SCHEMES: dict[str, str] = {"port": "serial", "can": "can", "udp": "udp"}
"""The shorthand options and the link scheme each one's value is the target of."""
SHORTHAND_OPTIONS: dict[str, tuple[str, ...]] = {
    "serial": ("baud",), "can": ("interface", "fd", "bitrate", "data_bitrate", "bus_kwargs"),
    "udp": ("bitrate",)}
"""The rate and layout options each shorthand's scheme takes, as its URL options."""
LINK_OPTIONS = ("baud", "interface", "fd", "bitrate", "data_bitrate", "bus_kwargs")
"""Every rate and layout option (dest names): each goes with the shorthands that take it."""


def bus_kwargs_value(text: str) -> str:
    """argparse type: ``--bus-kwargs`` (``KEY=VALUE,...`` or a JSON object), checked and
    written as the ``bus_kwargs`` option of a ``can:`` link URL."""
    try:
        return format_bus_kwargs(parse_bus_kwargs(text))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_transport_args(parser: argparse.ArgumentParser, udp_listen: bool = False,
                       required: bool = True,
                       title: str = "link (one of --link, --port, --can or --udp)") -> None:
    """Add the link options to ``parser`` (one of --link, --port, --can or --udp; required
    unless ``required`` is false, under the group heading ``title``).

    ``udp_listen``: this end is the host: it listens on a UDP address instead of sending to
    it (the board), and opens every link in the "host" role.
    """
    group = parser.add_argument_group(title)
    parser.set_defaults(udp_listen=udp_listen)
    which = group.add_mutually_exclusive_group(required=required)
    which.add_argument("--link", metavar="URL",
                       help="the link as a URL: serial:/dev/ttyUSB0?baud=921600, "
                            "can:vcan0?interface=socketcan&fd=1, udp:127.0.0.1:9000, pty: "
                            "(docs: Links)")
    which.add_argument("--port", metavar="PORT",
                       help="serial port: device path (/dev/ttyUSB0, /dev/pts/3) or pyserial "
                            "URL (loop://, socket://host:port); short for --link serial:PORT")
    which.add_argument("--can", metavar="CHANNEL",
                       help="CAN channel, e.g. can0 or vcan0 (python-can); short for "
                            "--link can:CHANNEL")
    if udp_listen:
        which.add_argument("--udp", metavar="[HOST:]PORT",
                           help="listen for boards on this UDP port (host default "
                                f"{UDP_LISTEN_HOST}; 0.0.0.0:PORT hears other machines)")
    else:
        which.add_argument("--udp", metavar="HOST:PORT",
                           help="send the serial packet stream in UDP datagrams to HOST:PORT")
    group.add_argument("--baud", type=baud_value, default=None, metavar="N",
                       help=f"serial baud rate, bits/s, 8N1, {MIN_BAUD}..{MAX_BAUD} (default: "
                            f"{DEFAULT_BAUD})")
    group.add_argument("--interface", default=None, metavar="NAME",
                       help="python-can interface: socketcan, virtual, pcan, kvaser, slcan, "
                            "udp_multicast, ... (default: python-can's own configuration, "
                            f"CAN_INTERFACE or ~/.canrc, else {DEFAULT_CAN_INTERFACE})")
    group.add_argument("--fd", action="store_true", default=None,
                       help="use CAN FD (64-byte frames)")
    group.add_argument("--bitrate", type=bitrate_value, default=None, metavar="N",
                       help=f"CAN (arbitration) bitrate, bits/s (default: {DEFAULT_CAN_BITRATE}"
                            f"); UDP wire budget (default: {DEFAULT_UDP_BITRATE})")
    group.add_argument("--data-bitrate", type=bitrate_value, default=None, metavar="N",
                       help="CAN FD data-phase bitrate, bits/s (default: same as --bitrate)")
    group.add_argument("--bus-kwargs", type=bus_kwargs_value, default=None,
                       metavar="KEY=VALUE,...",
                       help="further python-can Bus arguments for a vendor adapter, "
                            "KEY=VALUE,... or a JSON object (e.g. sjw_abr=8,tseg1_abr=31)")


def link_url(args: argparse.Namespace) -> LinkUrl | None:
    """The link :func:`add_transport_args`' options select, as a URL (None: no link given).

    Raises :class:`ConfigError` when a rate or layout option does not fit the link.
    """
    given = [name for name in LINK_OPTIONS if getattr(args, name, None) is not None]
    if getattr(args, "link", None) is not None:
        if given:
            raise ConfigError(f"--{given[0].replace('_', '-')} goes with --port, --can or "
                              "--udp; with --link write it in the URL (e.g. "
                              "serial:/dev/ttyUSB0?baud=115200)")
        return LinkUrl.parse(args.link)
    for option, scheme in SHORTHAND_SCHEMES.items():
        target = getattr(args, option, None)
        if target is None:
            continue
        for name in given:
            if name not in SHORTHAND_OPTIONS[scheme]:
                raise ConfigError(_misfit(name, option))
        if scheme == "udp" and args.udp_listen and ":" not in target:
            target = f"{UDP_LISTEN_HOST}:{target}"
        return LinkUrl.parse(format_url(scheme, target, **{
            name: getattr(args, name) for name in SHORTHAND_OPTIONS[scheme]}))
    return None


def _misfit(name: str, option: str) -> str:
    flag = f"--{name.replace('_', '-')}"
    takers = [f"--{o}" for o, s in SHORTHAND_SCHEMES.items() if name in SHORTHAND_OPTIONS[s]]
    return (f"{flag} does not go with --{option}: it is an option of {' and '.join(takers)}"
            + (" (a serial port's rate is --baud)" if name == "bitrate" else ""))


def link_role(args: argparse.Namespace) -> Role:
    """The role this command opens its link in: "host" (it listens) or "board"."""
    return "host" if args.udp_listen else "board"


def check_transport_args(args: argparse.Namespace) -> None:
    """:class:`ConfigError` when :func:`add_transport_args`' options do not fit together."""
    link_url(args)


def selected_link(args: argparse.Namespace) -> type[Transport[Any]]:
    """The class of the link the options select (its properties: payload, FD, units), not
    opened; :class:`ConfigError` when none is given."""
    return link_class(_required_url(args).scheme)


def selected_can_fd(args: argparse.Namespace) -> bool:
    """Whether the selected link is CAN FD, known before it is opened."""
    url = _required_url(args)
    return link_class(url.scheme).url_can_fd(url)


def transport_argv(args: argparse.Namespace) -> list[str]:
    """The link of ``args`` as a command line gives it (``--link URL``, for a ``skinhil
    serve`` another command starts on the same link); empty when no link is selected."""
    url = link_url(args)
    return [] if url is None else ["--link", str(url)]


def open_transport(args: argparse.Namespace) -> Transport[Any]:
    """Open the link selected by :func:`add_transport_args`' options.

    Raises :class:`skinhil.errors.TransportError` (link unusable, URL malformed) or
    :class:`ConfigError` (options that do not fit together).
    """
    return open_link(_required_url(args), link_role(args))


def describe_transport(args: argparse.Namespace) -> str:
    """A short description of the selected link, for status lines: its URL and role."""
    url = _required_url(args)
    return f"{url} ({'listening' if args.udp_listen else 'sending'})"


def serial_baud(args: argparse.Namespace) -> int:
    """The ``--baud`` given, else the default (bits/s)."""
    return DEFAULT_BAUD if args.baud is None else int(args.baud)


def _required_url(args: argparse.Namespace) -> LinkUrl:
    url = link_url(args)
    if url is None:
        raise ConfigError("give a link: --link URL, --port PORT (serial), --can CHANNEL "
                          "(CAN) or --udp HOST:PORT (UDP)")
    return url
