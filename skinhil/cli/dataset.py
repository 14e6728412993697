"""``skinhil dataset``: training data for decoders, a suite's cases simulated offline on
training seeds and written in the Spiking Heidelberg Digits' layout (docs/dataset.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from tqdm.auto import tqdm

from skinhil.cli.conventions import add_json_option, print_json
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.options import add_size_option, add_snr_option
from skinhil.dataset import check_training, dataset_cases, make_dataset, parse_seeds
from skinhil.output_files import check_output_path
from skinhil.suites import suite

OUT_SUFFIXES = (".h5", ".hdf5")
"""What ``--out`` may end in."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "dataset", help="write training data: a suite's trials simulated offline, as SHD",
        description="Simulate the cases of a task suite offline for training seeds, exactly "
                    "as 'skinhil serve --suite SUITE:CASE --seed N' plays them (same trials, "
                    "skin and neuron noise), and write one sample per trial (its spikes from "
                    "the trial's onset to the end of its answer window) with its label and "
                    "truth to an HDF5 file in the layout of the Spiking Heidelberg Digits "
                    "(spikes/times in s, spikes/units, labels, extra/...; tonic reads it). "
                    "Seeds outside the suite's training range are refused: evaluation "
                    "(bench --suite) draws from the others. Layout: docs/dataset.md.")
    p.add_argument("--suite", required=True, metavar="SUITE",
                   help="the suite, e.g. tactile-v1 (skinhil suites lists them)")
    p.add_argument("--seeds", required=True, metavar="SEEDS",
                   help="training seeds: whole numbers and ranges, e.g. 1-200 or 1,2,5-9")
    p.add_argument("--cases", metavar="CASE[,CASE...]",
                   help="only these cases (default: every case that poses one answered "
                        "task; a held object's case has no offline samples)")
    p.add_argument("--out", type=Path, required=True, help="output file (.h5)")
    add_snr_option(p)
    add_size_option(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_option(p)


def run(args: argparse.Namespace) -> int:
    the_suite = suite(args.suite)
    seeds = parse_seeds(args.seeds)
    check_training(the_suite, seeds)
    cases = dataset_cases(the_suite, None if args.cases is None else
                          [c.strip() for c in args.cases.split(",") if c.strip()])
    out = check_output_path(args.out, OUT_SUFFIXES)
    announce_cold_cache("dataset")
    with tqdm(total=len(seeds) * len(cases), unit="run", disable=args.no_progress) as bar:
        written = make_dataset(out, the_suite, seeds, cases, args.snr_db, args.size,
                               progress=lambda case, seed: bar.update(1))
    if args.json:
        print_json({"path": str(written.path), "samples": written.samples,
                    "spikes": written.spikes, "suite": the_suite.id,
                    "cases": [c.name for c in cases], "seeds": len(seeds),
                    "snr_db": args.snr_db})
        return 0
    print(f"wrote {written.path}: {written.samples} samples ({written.spikes} spikes) of "
          f"{the_suite.id} cases {', '.join(c.name for c in cases)} over {len(seeds)} "
          f"training seed(s) at {args.snr_db:g} dB")
    return 0
