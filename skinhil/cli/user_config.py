"""The configuration file's defaults (:mod:`skinhil.config`) applied to the command line: an
option given on the command line wins, the file fills what was not given.

:func:`prepare_parser` makes an option the file gives no longer required (``listen
--model``, the link of ``serve`` and ``listen``); :func:`apply_config` fills the parsed
arguments: the link when none was given (``link``, ``port`` or ``can``) and then the rate
and layout options that fit that link (``baud`` with a serial port, ``interface``,
``bitrate``, ``fd``, ``bus_kwargs`` with CAN), and ``model``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from skinhil.config import LINK_TARGET_KEYS, UserConfig

TARGET_OPTIONS = ("link", "port", "can", "udp")
"""The options (dest names) that choose a link."""


def _subparsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices.values())
    return []


def prepare_parser(parser: argparse.ArgumentParser, config: UserConfig) -> None:
    """Options the configuration gives are no longer required by the subcommands' parsers."""
    gives_link = any(k in config.values for k in LINK_TARGET_KEYS)
    for sub in _subparsers(parser):
        for action in sub._actions:
            if action.dest == "model" and "model" in config.values:
                action.required = False
        for group in sub._mutually_exclusive_groups:
            if gives_link and any(a.dest == "port" for a in group._group_actions):
                group.required = False


def apply_config(args: argparse.Namespace, config: UserConfig) -> None:
    """Fill in ``args`` what the command line did not give and the configuration does."""
    values = config.values
    if "model" in values and getattr(args, "model", False) is None:
        args.model = Path(values["model"])
    if not hasattr(args, "port"):
        return
    if all(getattr(args, name, None) is None for name in TARGET_OPTIONS):
        for key in LINK_TARGET_KEYS:
            if key in values:
                setattr(args, key, values[key])
    if getattr(args, "link", None) is not None:
        return  # a URL carries its own options
    from skinhil.cli.transport_args import SHORTHAND_OPTIONS, SHORTHAND_SCHEMES
    from skinhil.transports.can import format_bus_kwargs

    scheme = next((s for o, s in SHORTHAND_SCHEMES.items()
                   if getattr(args, o, None) is not None), None)
    for name in SHORTHAND_OPTIONS.get(scheme or "", ()):
        if name in values and getattr(args, name, None) is None:
            value = values[name]
            setattr(args, name, format_bus_kwargs(value) if name == "bus_kwargs" else value)
