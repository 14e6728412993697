"""``skinhil pty``: two linked serial devices (pty pair bridge) until Ctrl-C, for machines
without socat: ``skinhil serve --port A`` on one, a decoder under test on the other."""

from __future__ import annotations

import argparse
import sys

from skinhil.cli import signals
from skinhil.cli.conventions import add_json_option, print_json
from skinhil.transports.pty_bridge import PtyBridge


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "pty", help="two linked pty devices (a null-modem cable) until Ctrl-C",
        description="Make two pty devices joined back to back (what socat's 'pty,raw "
                    "pty,raw' makes) and print their paths, one per line; bytes written to "
                    "one are read from the other until Ctrl-C. Run 'skinhil serve --port' "
                    "on the first and your decoder on the second.")
    add_json_option(p)


def run(args: argparse.Namespace) -> int:
    with PtyBridge() as bridge:
        if args.json:
            print_json({"paths": list(bridge.paths)})
        else:
            print(bridge.paths[0], flush=True)
            print(bridge.paths[1], flush=True)
        if not args.quiet:
            print(f"skinhil pty: {bridge.paths[0]} <-> {bridge.paths[1]}; e.g. skinhil serve "
                  f"--port {bridge.paths[0]} and your decoder on {bridge.paths[1]}; "
                  "Ctrl-C ends", file=sys.stderr, flush=True)
        with signals.stop_event() as stop:
            bridge.run(stop)
    return 0
