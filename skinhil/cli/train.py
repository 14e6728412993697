"""``skinhil train``: fit the direction decoder on simulated Figure 4 trials and save it."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from skinhil.cli.options import snr_value
from skinhil.errors import ConfigError
from skinhil.receiver.training import BIN_S, WINDOW_S, TrainingReport, train_decoder


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "train", help="fit the force-direction decoder on simulated trials",
        description="Simulate the 9 direction conditions of the paper's Figure 4 (reps noisy "
                    f"trials each), PSP-filter the spikes, take the activity of all 338 "
                    f"sensors in {1e3 * BIN_S:g} ms bins over the first {1e3 * WINDOW_S:g} ms "
                    "after the onset, fit a linear SVM, print its repeated 5-fold "
                    "cross-validated accuracy and confusion matrix, and save it as plain "
                    "data (.npz + JSON metadata, no pickle).")
    p.add_argument("--out", type=Path, required=True, metavar="NPZ", help="decoder file")
    p.add_argument("--snr-db", type=snr_value, default=10.0, metavar="DB",
                   help="neuron noise SNR in dB, 'inf' for none (default: 10)")
    p.add_argument("--reps", type=int, default=50, help="trials per condition (default: 50)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default: 0)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def print_report(report: TrainingReport, names: dict[int, str]) -> None:
    """Cross-validated accuracy and confusion matrix as text."""
    print(f"cross-validated accuracy at {report.snr_db:g} dB ({report.reps} trials per "
          f"condition): {100 * report.cv_accuracy:.1f}% ± {100 * report.cv_accuracy_std:.1f}"
          f" (chance {100 / len(report.classes):.1f}%)")
    width = max(len(names.get(c, str(c))) for c in report.classes)
    print("confusion (rows: true, columns: predicted, summed over folds and repeats):")
    print(" " * width + " " + " ".join(f"{c:>5}" for c in report.classes))
    for c, row in zip(report.classes, report.confusion, strict=True):
        print(f"{names.get(c, str(c)):>{width}} " + " ".join(f"{int(v):>5}" for v in row))


def run(args: argparse.Namespace) -> int:
    from skinhil.cli.listen import class_names

    if args.reps < 2:
        raise ConfigError(f"--reps must be at least 2 (cross-validation), got {args.reps}")
    if math.isnan(args.snr_db):
        raise ConfigError("--snr-db must be a number of dB or inf")
    t0 = time.monotonic()
    decoder, report = train_decoder(args.snr_db, args.reps, args.seed,
                                    progress=not args.no_progress)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    decoder.save(args.out)
    print_report(report, class_names())
    print(f"wrote {args.out} in {time.monotonic() - t0:.1f} s")
    return 0
