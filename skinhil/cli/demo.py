"""``skinhil demo``: board → pty → receiver, live predictions, then accuracy, latency, loss.

No hardware needed: a raw pty pair (``os.openpty()``, a real tty) joins a board, run as
``skinhil serve --port <pty slave>`` in a subprocess (its own core and clock), to the
reference receiver here, reading the pty master. The board plays its seeded random sequence
of the 9 direction conditions with ground-truth markers; the receiver decides each stimulus
from the activity alone and the markers score it. The receiver also answers each decision
to the board as a DECISION (as ``listen --answer``), and the board's scoreboard of it (the
way it scores any decoder under test) is shown beside the receiver's own.

The model is ``--model FILE`` or, by default, one trained on first use at the demo's SNR
and cached under ``$XDG_CACHE_HOME/skinhil`` (``~/.cache/skinhil``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from skinhil.cli import demo_grasp
from skinhil.cli.conventions import MODEL_HELP, add_json_option, print_json
from skinhil.cli.demo_cache import DEMO_REST_S, cached_model
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.lab_outputs import (
    add_lab_output_args,
    check_lab_outputs,
    lab_outputs,
    provenance,
)
from skinhil.cli.listen import LivePrinter, class_names, print_summary, summary
from skinhil.cli.options import add_seed_option, add_snr_option
from skinhil.cli.transport_args import baud_value
from skinhil.cli.values import integer, real
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, spring_count
from skinhil.model.skin import SkinParams
from skinhil.receiver import DecisionAnswerer, Receiver
from skinhil.receiver.model_file import load_window_decoder
from skinhil.receiver.session import run_against_board, serve_command
from skinhil.temp_folders import TempFolder
from skinhil.transports import DEFAULT_BAUD, PtyMasterTransport

DEFAULT_LIFTS = 10
"""Lifts of ``--task grasp`` (about 1.2 s each)."""
MAX_LIFTS = 64
"""Most lifts of one run (one contact each)."""
DEFAULT_DURATION_S = 20.0
MIN_DURATION_S = 1.0
"""Shortest demo (s of board time): a stimulus and its rest, so that there is something to
decide."""
MAX_DURATION_S = 3600.0
"""Longest demo (s of board time)."""
DEMO_SEED = 1
"""The demo board's default seed (printed in its banner, the serve command it starts)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "demo", help="board and receiver joined by a pty: live predictions, accuracy, latency",
        description="Start the emulated board and the reference receiver joined by a pty "
                    "pair, play a random sequence of the 9 direction conditions, print each "
                    "online decision and end with accuracy, latency and loss figures. Trains "
                    "and caches a model on first use.")
    add_snr_option(p)
    p.add_argument("--duration", dest="duration_s",
                   type=real(MIN_DURATION_S, MAX_DURATION_S, "seconds"),
                   default=DEFAULT_DURATION_S,
                   metavar="SECONDS", help=f"board time to play, {MIN_DURATION_S:g}.."
                                           f"{MAX_DURATION_S:g} (default: "
                                           f"{DEFAULT_DURATION_S:g})")
    add_seed_option(p, DEMO_SEED)
    p.add_argument("--model", type=Path, metavar="NPZ", help=MODEL_HELP)
    p.add_argument("--baud", type=baud_value, default=DEFAULT_BAUD,
                   help=f"emulated serial baud rate (default: {DEFAULT_BAUD})")
    p.add_argument("--task", choices=("directions", "grasp"), default="directions",
                   help="directions: decide the 9 direction conditions (default); grasp: the "
                        "board holds an object through --lifts lifts and the reference grip "
                        "controller grips it from the spikes (docs: Grasp)")
    p.add_argument("--lifts", type=integer(1, MAX_LIFTS, "lifts"), default=DEFAULT_LIFTS,
                   metavar="N", help=f"--task grasp: lifts to play, 1..{MAX_LIFTS} (default: "
                                     f"{DEFAULT_LIFTS}, about {DEFAULT_LIFTS * 1.2:g} s)")
    p.add_argument("--controller", choices=("reflex", "off"), default="reflex",
                   help="--task grasp: the reference grip controller (default), or none: the "
                        "hand keeps its constant low grip")
    add_lab_output_args(p)
    add_json_option(p)


def print_beside(own: dict[str, Any], board: dict[str, Any]) -> None:
    """The receiver's scoring of itself beside the board's scoring of its DECISIONs."""
    def pct(v: float | None) -> str:
        return "n/a" if v is None else f"{100 * v:.1f} %"

    def lat(d: dict[str, Any]) -> str:
        return "n/a" if d["p50"] is None else f"{d['p50']:.1f} / {d['p99']:.1f}"

    rows = [("accuracy", pct(own["accuracy"]), pct(board["accuracy"])),
            ("right / scored stimuli", f"{own['correct']}/{own['stimuli_scored']}",
             f"{board['right']}/{board['matched'] + board['misses']}"),
            ("missed", str(own["misses"]), str(board["misses"])),
            ("unmatched decisions", str(own["false_alarms"]),
             str(board["false_alarms"] + board["duplicates"] + board["late"])),
            ("latency p50 / p99 (ms)", lat(own["decision_latency_board_ms"]),
             lat(board["latency_ms"]))]
    print(f"{'scored by':<24}{'the receiver itself':>21}{'the board (its DECISIONs)':>28}")
    for name, a, b in rows:
        print(f"{name:<24}{a:>21}{b:>28}")
    print("(latency: the receiver's from onset to its decision; the board's from onset to the "
          f"DECISION's arrival; {board['pending']} stimuli still open when the board stopped)")


def run(args: argparse.Namespace) -> int:
    """The demo; with ``--json`` everything it prints goes to stderr and its result is one
    JSON object on stdout."""
    if not args.json:
        _play(args)
        return 0
    with contextlib.redirect_stdout(sys.stderr):
        result = _play(args)
    print_json(result)
    return 0


def _play(args: argparse.Namespace) -> dict[str, Any]:
    """Play the task of ``args``; its result (``--json``'s object)."""
    if args.task == "grasp":
        return demo_grasp.run(args)
    if args.lifts != DEFAULT_LIFTS or args.controller != "reflex":
        raise ConfigError("--lifts and --controller set the grasp demo: add --task grasp, or "
                          "drop them")
    check_lab_outputs(args, PAPER_SIZE)
    t_start = time.monotonic()
    announce_cold_cache("demo")
    model_path = (args.model if args.model is not None
                  else cached_model(args.snr_db, args.quiet, args.baud, args.seed))
    decoder = load_window_decoder(model_path, n_channels=spring_count(PAPER_SIZE))
    link, slave_fd = PtyMasterTransport.open_pair(args.baud)
    score_dir = TempFolder("demo")
    score = score_dir.path / "score.json"
    cmd = serve_command(["--port", link.slave_path, "--baud", str(args.baud), "--score",
                         str(score), "--markers"], args.duration_s, args.snr_db, args.seed,
                        DEMO_REST_S)
    names = class_names()
    receiver = Receiver(link, decoder)
    answerer = DecisionAnswerer(receiver)
    receiver.add_listener(answerer)
    if not args.quiet:
        receiver.add_listener(LivePrinter(receiver, False, names))
    print(f"board: {' '.join(cmd[1:])}; mechanics {SkinParams().describe_mechanics()}\n"
          f"receiver: {link.name}, model {model_path}", flush=True)
    t_link = time.monotonic()
    try:
        prov = {**provenance(f"pty {link.slave_path} @ {args.baud} baud", model_path),
                "snr_db": f"{args.snr_db:g}", "seed": str(args.seed)}  # the demo runs its board
        with lab_outputs(args, receiver, names, PAPER_SIZE, "demo", answerer.as_dict, prov):
            status, out, err = run_against_board(receiver, cmd)
    except KeyboardInterrupt:  # stopped: the figures so far
        print()
        print_summary(summary(receiver, time.monotonic() - t_link), names)
        print(f"demo: stopped after {time.monotonic() - t_start:.1f} s wall", flush=True)
        raise
    finally:
        link.shutdown()
        os.close(slave_fd)
    with score_dir:
        board_score = json.loads(score.read_text(encoding="utf-8")) if score.exists() else None
    if status != 0:
        raise ConfigError(f"the board stopped with status {status}: "
                          f"{err.strip().splitlines()[-1] if err.strip() else 'no message'}")
    info = summary(receiver, time.monotonic() - t_link)
    wall_s = time.monotonic() - t_start
    if not args.json:
        print()
        print_summary(info, names)
        if board_score is not None:
            print_beside(info, board_score)
        if out.strip():
            print(f"board: {out.strip().splitlines()[-1]}")
        print(f"demo: {args.duration_s:g} s of board time at {args.snr_db:g} dB, "
              f"{wall_s:.1f} s wall in all")
    return {"task": "directions", "duration_s": args.duration_s, "snr_db": args.snr_db,
            "seed": args.seed, "model": str(Path(model_path).resolve()),
            "receiver": info, "board_score": board_score,
            "wall_s": round(wall_s, 3)}

