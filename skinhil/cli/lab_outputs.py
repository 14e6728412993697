"""The lab outputs of a receiving command (``listen``, ``demo``): ``--view`` (the live view
in the browser) and ``--lsl`` (Lab Streaming Layer outlets), one helper for both commands,
for one board or several on one link (``listen --udp``, ``listen --can --board-id 0,5``):
one view server whose page lists the boards, and each board's LSL streams (the first
board's named NAME-..., each further board's NAME-2-..., NAME-3-... in the order they first
sent; their desc says which board)."""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import sys
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path

from skinhil.errors import ConfigError
from skinhil.lsl import LslOutlets, require_pylsl
from skinhil.model.geometry import MeshSize, build_mesh, format_size, spring_count
from skinhil.model.skin import SkinParams
from skinhil.receiver import Receiver, ReceiverListener
from skinhil.view import ViewFeed, ViewServer, parse_address
from skinhil.view.feed import StreamSource
from skinhil.view.grasp_trace import GraspTrace
from skinhil.view.truth_onsets import TruthTail


def _sensors(text: str) -> list[int]:
    try:
        return [int(v, 0) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give sensor addresses such as 0,17,42") \
            from None


MAX_LSL_NAME_CHARS = 64
"""Longest LSL stream name prefix (the outlets add ``-spikes``, ``-psp``, ...)."""


def _lsl_name(text: str) -> str:
    """argparse type of ``--lsl NAME``: 1..64 printable characters."""
    if not (0 < len(text) <= MAX_LSL_NAME_CHARS and text.isprintable() and text.strip()):
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r}{'...' if len(text) > 40 else ''}: give a stream name of 1.."
            f"{MAX_LSL_NAME_CHARS} printable characters, such as skinhil")
    return text


def add_lab_output_args(parser: argparse.ArgumentParser, lsl: bool = True,
                        truth: bool = False) -> None:
    """Add ``--view [HOST:]PORT``, ``--psp-sensors``, (with ``lsl``) ``--lsl [NAME]`` and
    (with ``truth``) ``--view-truth FILE``, the operator's truth the view draws."""
    parser.add_argument("--view", metavar="[HOST:]PORT",
                        help="serve the live view (raster, PSP traces, decisions, counters) "
                             "at http://HOST:PORT/ (host 127.0.0.1 unless given; port 0: "
                             "any free port, printed)")
    parser.add_argument("--psp-sensors", type=_sensors, metavar="N[,N...]",
                        help="sensor addresses whose PSP traces the view shows and the LSL "
                             "psp outlet carries (default: 8 spread over the skin in the "
                             "view, every sensor on LSL)")
    if truth:
        parser.add_argument("--view-truth", type=Path, metavar="FILE",
                            help="with --view: draw the onsets of the board's truth file "
                                 "(serve --truth FILE: stimulus markers and contact trials) "
                                 "on the raster too, read as it appears or grows")
    if lsl:
        parser.add_argument("--lsl", nargs="?", const="skinhil", metavar="NAME", type=_lsl_name,
                            help="publish LSL outlets NAME-spikes, NAME-psp, NAME-markers, "
                                 "NAME-decisions, NAME-link (default NAME: skinhil; with "
                                 "several boards the further ones' NAME-2-..., NAME-3-...; "
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
    if getattr(args, "view_truth", None) is not None and args.view is None:
        raise ConfigError("--view-truth FILE draws the truth on the live view: add --view PORT")
    n = spring_count(size)
    if args.psp_sensors is not None and not all(0 <= a < n for a in args.psp_sensors):
        raise ConfigError(f"--psp-sensors {','.join(map(str, args.psp_sensors))}: a skin of "
                          f"{format_size(size)} has sensors 0..{n - 1} — give addresses "
                          "in that range")


def provenance(link: str, decoder: Path | None) -> dict[str, str]:
    """What the LSL streams say of the run (:mod:`skinhil.lsl.metadata`): the link, the
    decoder file and its SHA-256; the board's SNR and seed are not on the wire."""
    out = {"link": link, "snr_db": "unknown (not sent by the board)",
           "seed": "unknown (not sent by the board)"}
    if decoder is not None:
        out["decoder"] = str(Path(decoder).absolute())
        try:
            out["decoder_sha256"] = hashlib.sha256(Path(decoder).read_bytes()).hexdigest()
        except OSError:
            pass
    return out


class LabOutputs:
    """The view server and the LSL outlets asked for by ``args``; :meth:`attach` gives a
    board's receiver its listeners (the view's feed, the outlets)."""

    def __init__(self, args: argparse.Namespace, names: dict[int, str], size: MeshSize,
                 command: str, prov: Mapping[str, str] | None = None) -> None:
        p = SkinParams(size=size)
        self.mesh = build_mesh(p.spacing_m, p.layer_gap_m, p.size)
        self.args, self.names, self.command = args, names, command
        self.provenance = dict(prov or {})
        self.server: ViewServer | None = None
        self.outlets: list[LslOutlets] = []
        self.truth_tails: list[TruthTail] = []
        self.boards = 0
        if args.view is not None:
            host, port = parse_address(args.view)
            self.server = ViewServer(None, host, port).start()
            print(f"skinhil {command}: live view at {self.server.url}", file=sys.stderr,
                  flush=True)

    def view_feed(self, key: object, source: StreamSource,
                  answers: Callable[[], dict[str, int]] | None = None,
                  grasp: GraspTrace | None = None) -> ViewFeed | None:
        """Board ``key``'s feed on the view (None without ``--view``): it hears ``source``
        (a receiver, or the grasp demo's loop, whose ``grasp`` truth it plots too)."""
        if self.server is None:
            return None
        feed = ViewFeed(source, self.mesh, self.names, self.args.psp_sensors, answers, grasp)
        self.server.add_feed(str(key), feed)
        truth = getattr(self.args, "view_truth", None)
        if truth is not None:
            self.truth_tails.append(TruthTail(truth, feed.add_truth_onsets).start())
        return feed

    def attach(self, key: object, receiver: Receiver,
               answers: Callable[[], dict[str, int]] | None = None) -> list[ReceiverListener]:
        """The listeners of board ``key``'s ``receiver`` (the view also shows ``answers()``,
        the receiver's DECISION counters, when it answers the board)."""
        self.boards += 1
        out: list[ReceiverListener] = []
        feed = self.view_feed(key, receiver, answers)
        if feed is not None:
            out.append(feed)
        if getattr(self.args, "lsl", None) is not None:
            name = self.args.lsl if self.boards == 1 else f"{self.args.lsl}-{self.boards}"
            outlets = LslOutlets(receiver, self.mesh, self.names, name,
                                 self.args.psp_sensors, {**self.provenance, "board": str(key)})
            self.outlets.append(outlets)
            out.append(outlets)
            print(f"skinhil {self.command}: LSL outlets {name}-spikes, -psp, -markers, "
                  f"-decisions, -link (board {key})", file=sys.stderr, flush=True)
        return out

    def close(self) -> None:
        """End the view's run and close the outlets (they push what they kept)."""
        for tail in self.truth_tails:
            tail.close()
        if self.server is not None:
            self.server.close()
        for outlets in self.outlets:
            outlets.close()


@contextlib.contextmanager
def lab_outputs(args: argparse.Namespace, receiver: Receiver, names: dict[int, str],
                size: MeshSize, command: str,
                answers: Callable[[], dict[str, int]] | None = None,
                prov: Mapping[str, str] | None = None) -> Iterator[LabOutputs]:
    """While the body runs, the view and the LSL outlets asked for by ``args`` hear
    ``receiver`` (see :meth:`LabOutputs.attach`); the view's address goes to stderr."""
    outputs = None
    try:
        outputs = LabOutputs(args, names, size, command, prov)
        for listener in outputs.attach(receiver.board_id, receiver, answers):
            receiver.add_listener(listener)
        yield outputs
    finally:
        if outputs is not None:
            outputs.close()
