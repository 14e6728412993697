"""``skinhil reproduce``: regenerate the paper's figures and REPORT.md."""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from skinhil.cli.conventions import add_json_option, print_json
from skinhil.cli.values import integer
from skinhil.reproduce import ReproduceConfig, reproduce
from skinhil.reproduce.report import verdicts
from skinhil.reproduce.run import ReproduceOutcome


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "reproduce", help="regenerate the paper's figures and a report of its claims",
        description="Simulate, analyse and plot Figures 1E-F, 2A-C (and the tension axis), "
                    "3A-F, 4A-G and Supplementary 1 for the linear and the geometric "
                    "mechanics, each with the length and the axial readout, at the paper's "
                    "amplitude and at 1/100 of its strain, search the paper's linear model "
                    "for a setting that reproduces its claims, and write "
                    "REPORT.md saying which claims of the paper the model reproduces (needs "
                    "matplotlib).")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="output directory")
    p.add_argument("--quick", action="store_true",
                   help="small grids, few repeats, the paper's amplitude only (a check, "
                        "for tests; docs: Reproduce the paper)")
    p.add_argument("--workers", type=integer(1, 256, "worker count"), metavar="N",
                   help="local worker processes for sweeps and cross-validation "
                        "(default: all cores)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run the sweeps on this Dask distributed scheduler")
    p.add_argument("--grid", type=integer(1, 101, "grid side"), metavar="N",
                   help="N x N stiffness x damping grid for both mechanics (default: 11, "
                        "--quick: 5 and 3)")
    p.add_argument("--repeats", type=integer(1, 1000, "count"), metavar="R",
                   help="cross-validation repeats (default: 5, --quick: 2)")
    p.add_argument("--search-only", action="store_true",
                   help="run only the paper preset's search (the paper's linear model, its "
                        "open choices searched) and cache it in DIR/paper_search.json, which "
                        "a later run in DIR reads")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_option(p)


def run(args: argparse.Namespace) -> int:
    cfg = ReproduceConfig.quick() if args.quick else ReproduceConfig()
    cfg = replace(cfg, workers=args.workers, scheduler=args.scheduler,
                  progress=not args.no_progress)
    if args.grid is not None:
        cfg = replace(cfg, sweep_linear=(args.grid, args.grid),
                      sweep_geometric=(args.grid, args.grid))
    if args.repeats is not None:
        cfg = replace(cfg, decoding=replace(cfg.decoding, repeats=args.repeats))
    t0 = time.monotonic()
    try:
        outcome = reproduce(args.out, cfg, quick=args.quick, search_only=args.search_only)
    except KeyboardInterrupt:
        done = sorted(p.name for p in Path(args.out).glob("*") if not p.name.startswith("."))
        print(f"reproduce: stopped after {time.monotonic() - t0:.1f} s; {len(done)} files "
              f"complete in {args.out}{': ' + ', '.join(done) if done else ''}", flush=True,
              file=sys.stderr if args.json else sys.stdout)
        raise
    if args.json:
        print_json(as_json(outcome, search_only=args.search_only))
        return 0
    if args.search_only:
        print(f"wrote {outcome.report} in {outcome.seconds:.1f} s")
        return 0
    print(f"wrote {outcome.report} and {len(outcome.figures)} figures in "
          f"{outcome.seconds:.1f} s")
    for r in outcome.results:
        for v, _ in verdicts(r):
            print(f"  {r.label:24s} {v.key:4s} {'yes' if v.reproduced else 'NO ':3s}  "
                  f"{v.claim}")
    return 0


def as_json(outcome: ReproduceOutcome, search_only: bool) -> dict[str, object]:
    """``--json``'s object: the report's path, the figures written, the wall time (s) and,
    per run (mechanics/readout/amplitude), each claim's verdict."""
    return {"report": str(outcome.report.resolve()), "search_only": search_only,
            "figures": [str(f.resolve()) for f in outcome.figures],
            "seconds": round(outcome.seconds, 3),
            "runs": {r.label: [{"claim": v.key, "text": v.claim, "reproduced": v.reproduced}
                               for v, _ in verdicts(r)] for r in outcome.results}}
