"""The lab outputs of a receiving command (``listen``, ``demo``): ``--view`` (the live view
in the browser) and ``--lsl`` (Lab Streaming Layer outlets), one helper for both commands."""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Callable, Iterator

from skinhil.errors import ConfigError
from skinhil.lsl import LslOutlets, require_pylsl
from skinhil.model.geometry import MeshSize, build_mesh, format_size, spring_count
from skinhil.model.skin import SkinParams
from skinhil.receiver import Receiver
from skinhil.view import ViewFeed, ViewServer, parse_address


def _sensors(text: str) -> list[int]:
    try:
        return [int(v, 0) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give sensor addresses such as 0,17,42") \
            from None


def add_lab_output_args(parser: argparse.ArgumentParser, lsl: bool = True) -> None:
    """Add ``--view [HOST:]PORT``, ``--psp-sensors`` and (with ``lsl``) ``--lsl [NAME]``."""
    parser.add_argument("--view", metavar="[HOST:]PORT",
                        help="serve the live view (raster, PSP traces, decisions, counters) "
                             "at http://HOST:PORT/ (host 127.0.0.1 unless given; port 0: "
                             "any free port, printed)")
    parser.add_argument("--psp-sensors", type=_sensors, metavar="N[,N...]",
                        help="sensor addresses whose PSP traces the view shows and the LSL "
                             "psp outlet carries (default: 8 spread over the skin in the "
                             "view, every sensor on LSL)")
    if lsl:
        parser.add_argument("--lsl", nargs="?", const="skinhil", metavar="NAME",
                            help="publish LSL outlets NAME-spikes, NAME-psp, NAME-markers, "
                                 "NAME-decisions (default NAME: skinhil; "
                                 "pip install \"skinhil[lsl]\")")


def check_lab_outputs(args: argparse.Namespace, size: MeshSize) -> None:
    """Refuse what cannot run before anything starts (a missing pylsl, a bad address, PSP
    sensors that a skin of ``size`` does not have)."""
    if getattr(args, "lsl", None) is not None:
        require_pylsl()
        if not args.lsl.strip():
            raise ConfigError("--lsl NAME is empty — give a stream name such as skinhil")
    if args.view is not None:
        parse_address(args.view)
    n = spring_count(size)
    if args.psp_sensors is not None and not all(0 <= a < n for a in args.psp_sensors):
        raise ConfigError(f"--psp-sensors {','.join(map(str, args.psp_sensors))}: a skin of "
                          f"{format_size(size)} has sensors 0..{n - 1} — give addresses "
                          "in that range")


@contextlib.contextmanager
def lab_outputs(args: argparse.Namespace, receiver: Receiver, names: dict[int, str],
                size: MeshSize, command: str,
                answers: Callable[[], dict[str, int]] | None = None) -> Iterator[None]:
    """While the body runs, the view and the LSL outlets asked for by ``args`` hear
    ``receiver`` (the view also shows ``answers()``, the receiver's DECISION counters, when
    it answers the board); the view's address goes to stderr."""
    p = SkinParams(size=size)
    mesh = build_mesh(p.spacing_m, p.layer_gap_m, p.size)
    server = outlets = None
    try:
        if args.view is not None:
            host, port = parse_address(args.view)
            feed = ViewFeed(receiver, mesh, names, args.psp_sensors, answers)
            server = ViewServer(feed, host, port).start()
            receiver.add_listener(feed)
            print(f"skinhil {command}: live view at {server.url}", file=sys.stderr, flush=True)
        if getattr(args, "lsl", None) is not None:
            outlets = LslOutlets(receiver, mesh, names, args.lsl, args.psp_sensors)
            receiver.add_listener(outlets)
            print(f"skinhil {command}: LSL outlets {args.lsl}-spikes, -psp, -markers, "
                  "-decisions", file=sys.stderr, flush=True)
        yield
    finally:
        if server is not None:
            server.close()
        if outlets is not None:
            outlets.close()
