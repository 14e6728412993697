"""``skinhil train``: fit the direction decoder on a simulated board stream and save it."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from skinhil.cli.conventions import add_json_option, print_json
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.options import (
    SCHEDULE_HELP,
    add_seed_option,
    add_size_option,
    add_snr_option,
    read_scenario,
)
from skinhil.cli.values import MAX_REST_S, integer, real
from skinhil.model.timeline import DEFAULT_REST_S
from skinhil.output_files import check_output_path
from skinhil.receiver.training import BIN_S, WINDOW_S, TrainingReport, train_decoder

MAX_REPS = 10_000
"""Most stimuli per condition."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "train", help="fit the force-direction decoder on a simulated board stream",
        description="Simulate what the board plays (its seeded random sequence of the 9 "
                    "direction conditions of the paper's Figure 4, 9 x reps stimuli with "
                    "rests, at the given SNR), cut it into windows with the receiver's own "
                    "onset detector, label each window by the ground-truth marker it matches, "
                    "take the PSP activity of all sensors (338 at 6x6) in "
                    f"{1e3 * BIN_S:g} ms bins over {1e3 * WINDOW_S:g} ms, fit a linear SVM, "
                    "print its repeated 5-fold cross-validated accuracy (missed onsets count "
                    "as wrong, as online) and confusion matrix, and save it as plain data "
                    "(.npz + JSON metadata, no pickle). Train at the SNR and rest of the "
                    "board you will decode.")
    p.add_argument("--out", type=Path, required=True, metavar="NPZ", help="decoder file")
    add_snr_option(p)
    p.add_argument("--reps", type=integer(1, MAX_REPS, "count"), default=50,
                   help=f"stimuli per condition on average (9 x reps in all), 1..{MAX_REPS} "
                        "(default: 50)")
    p.add_argument("--rest", dest="rest_s", type=real(0, MAX_REST_S, "seconds"),
                   default=DEFAULT_REST_S,
                   metavar="SECONDS", help="rest after each stimulus, as the board's --rest "
                                           f"(default: {DEFAULT_REST_S:g})")
    add_seed_option(p)
    p.add_argument("--schedule", type=Path, metavar="TOML",
                   help=f"train on this {SCHEDULE_HELP} played once, as serve --schedule "
                        "plays it (its stimuli are the classes, its contacts touch the skin "
                        "meanwhile), instead of the random direction conditions; --reps and "
                        "--rest then do not apply")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_option(p)
    add_size_option(p)


def print_report(report: TrainingReport, names: dict[int, str]) -> None:
    """Offline accuracy, detection figures and confusion matrix as text."""
    print(f"offline accuracy at {report.snr_db:g} dB, rest {report.rest_s:g} s: "
          f"{100 * report.accuracy:.1f}% of {report.markers} stimuli (cross-validated "
          f"window accuracy {100 * report.window_accuracy:.1f}% ± "
          f"{100 * report.window_accuracy_std:.1f} on {report.decodable_windows} of "
          f"{report.windows} detected windows; "
          f"{report.misses} onsets missed, {report.false_alarms} false alarms; chance "
          f"{100 / max(1, len(report.classes)):.1f}%)")
    width = max(len(names.get(c, str(c))) for c in report.classes)
    print("confusion of the windows (rows: true, columns: predicted, summed over folds and "
          "repeats):")
    print(" " * width + " " + " ".join(f"{c:>5}" for c in report.classes))
    for c, row in zip(report.classes, report.confusion, strict=True):
        print(f"{names.get(c, str(c)):>{width}} " + " ".join(f"{int(v):>5}" for v in row))


def run(args: argparse.Namespace) -> int:
    from skinhil.cli.direction_names import class_names

    out = check_output_path(args.out, (".npz",))  # before minutes of training
    scenario = None
    if args.schedule is not None:
        played = read_scenario(args.schedule, args.size)
        scenario = (played.schedule, played.scene)
    announce_cold_cache("train")
    t0 = time.monotonic()
    try:
        decoder, report = train_decoder(args.snr_db, args.reps, args.seed, rest_s=args.rest_s,
                                        progress=not args.no_progress, size=args.size,
                                        scenario=scenario)
    except KeyboardInterrupt:
        kept = "the previous file kept" if out.exists() else "nothing written"
        print(f"train: stopped after {time.monotonic() - t0:.1f} s of training; {kept} "
              f"({out})", flush=True)
        raise
    decoder.save(out)
    if args.json:
        print_json({"path": str(out), "seconds": round(time.monotonic() - t0, 3),
                    "snr_db": report.snr_db, "rest_s": report.rest_s, "seed": report.seed,
                    "stimuli": report.markers, "accuracy": report.accuracy,
                    "window_accuracy": report.window_accuracy,
                    "window_accuracy_std": report.window_accuracy_std,
                    "windows": report.windows, "decodable_windows": report.decodable_windows,
                    "misses": report.misses, "false_alarms": report.false_alarms,
                    "classes": [int(c) for c in report.classes],
                    "confusion": [[int(v) for v in row] for row in report.confusion]})
        return 0
    print_report(report, class_names())
    print(f"wrote {out} in {time.monotonic() - t0:.1f} s")
    return 0
