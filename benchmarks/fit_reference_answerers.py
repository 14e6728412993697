"""Refits the reference answerers' parameters (skinhil/receiver/task_decoders.py: the FORCE
line, the VIBRATION classes, the SLIP channels) on training seeds of the suite only, and
stores them with their provenance (suite, version, seeds, SNR, this command) in
skinhil/data/reference_fit.json, which task_decoders.py reads:

    python benchmarks/fit_reference_answerers.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_reference_answerers.py --smoke     # runs, writes nothing

Each fit is its own script's (fit_force_line.py, fit_vibration_classes.py,
fit_slip_channels.py), on calibration runs of the suite's cases simulated offline exactly as
``skinhil serve --suite`` plays them (task_calibration.py). A seed outside the suite's training
range is refused: the README's scores, measured on evaluation seeds, are of seeds no fit saw.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import fit_force_line
import fit_slip_channels
import fit_vibration_classes
from task_calibration import REPO, SEEDS, SMOKE_TRIALS, SUITE

sys.path.insert(0, str(REPO))

from skinhil import __version__  # noqa: E402
from skinhil.dataset import check_training, parse_seeds  # noqa: E402
from skinhil.output_files import write_text  # noqa: E402
from skinhil.suites import suite  # noqa: E402

OUT = REPO / "skinhil" / "data" / "reference_fit.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seeds", default=SEEDS, help=f"training seeds of {SUITE}, e.g. {SEEDS}")
    ap.add_argument("--smoke", action="store_true",
                    help=f"one seed, {SMOKE_TRIALS} trials a case (a check that it runs)")
    ap.add_argument("--out", type=Path, default=None,
                    help=f"where to write the fit (default {OUT.relative_to(REPO)}; with "
                         "--smoke, nothing is written unless --out is given)")
    args = ap.parse_args()
    the_suite = suite(SUITE)
    seeds = parse_seeds(args.seeds)
    check_training(the_suite, seeds)
    trials = SMOKE_TRIALS if args.smoke else None
    if args.smoke:
        seeds = seeds[:1]
    vibration = fit_vibration_classes.fit(args.snr_db, seeds, trials)
    if vibration is None and not args.smoke:
        raise SystemExit("some vibration class had no touch: give more seeds")
    fitted = {
        "about": "the reference answerers' fitted parameters (skinhil/receiver/"
                 "task_decoders.py), fitted on training seeds of the suite only",
        "command": (f"python benchmarks/fit_reference_answerers.py --snr-db {args.snr_db:g} "
                    f"--seeds {args.seeds}" + (" --smoke" if args.smoke else "")),
        "suite": the_suite.id, "suite_name": the_suite.name,
        "suite_version": the_suite.version, "seeds": seeds, "snr_db": args.snr_db,
        "skin": "default (6x6)", "skinhil_version": __version__,
        "force": fit_force_line.fit(args.snr_db, seeds, trials),
        "vibration": vibration,
        "slip": fit_slip_channels.fit(args.snr_db, seeds, trials),
    }
    text = json.dumps(fitted, indent=1) + "\n"
    print(text)
    out = args.out or (None if args.smoke else OUT)
    if out is None:  # a smoke run's fit is no fit to use: the package's file stays
        return
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, text)
    print(f"wrote {out}: force {fitted['force']}; vibration {vibration}; "
          f"slip {fitted['slip']}")


if __name__ == "__main__":
    main()
