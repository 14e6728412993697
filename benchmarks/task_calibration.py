"""What the reference task decoders' fits share (fit_force_line.py, fit_vibration_classes.py,
fit_slip_channels.py, fit_reference_answerers.py): their command line, the calibration runs
and the touches the receiver's own onset rule finds in them.

A calibration run is a case of the suite :data:`SUITE` on a training seed, simulated offline
exactly as ``skinhil serve --suite SUITE:CASE --seed N`` plays it
(:func:`skinhil.dataset.simulate`): the fits never see an evaluation seed's trials, and a
seed outside the training range is refused."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from skinhil.dataset import check_training, parse_seeds, simulate  # noqa: E402
from skinhil.receiver.onset import OnsetDetector  # noqa: E402
from skinhil.receiver.params import OnsetParams  # noqa: E402
from skinhil.receiver.touch_kind import TOUCH_DOWN, in_layer, touch_kind  # noqa: E402
from skinhil.suites import Trials, suite  # noqa: E402

SUITE = "tactile-v1"
"""The suite whose cases calibrate the reference decoders."""
SEEDS = "1-20"
"""The fits' default training seeds."""

STEP_US = 100
"""The receiver's step (µs) the onsets are found on."""
MATCH_US = 50_000
"""An onset this long (µs) at most after a touch-down is that touch's (the others, releases
and noise, are left out)."""
RELEASE_US = (-20_000, 60_000)
"""An onset within this (µs) of a touch's last touching tick is its release's."""
SMOKE_TRIALS = 4
"""--smoke: trials of a case played (its first)."""


def calibration_args(doc: str, seeds: str = SEEDS) -> tuple[float, list[int], int | None]:
    """The command line of a fit: its SNR (dB), training seeds and trials per case (None:
    all of them)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seeds", default=seeds,
                    help=f"the calibration runs' training seeds of {SUITE}, e.g. 1-20")
    ap.add_argument("--smoke", action="store_true",
                    help=f"one seed, the first {SMOKE_TRIALS} trials of a case only (a check "
                         "that the script runs, not a fit to use)")
    args = ap.parse_args()
    chosen = parse_seeds(args.seeds)
    check_training(suite(SUITE), chosen)
    if args.smoke:
        return args.snr_db, chosen[:1], SMOKE_TRIALS
    return args.snr_db, chosen, None


def case_trials(case: str, seed: int, trials: int | None = None) -> Trials:
    """The trials of :data:`SUITE`'s ``case`` for training seed ``seed`` (its first
    ``trials``; None: all)."""
    s = suite(SUITE)
    return s.case(case).generate(s.id, seed, trials=trials)


def calibration_run(case: str, snr_db: float, seed: int,
                    trials: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The events and the contact truth of :data:`SUITE`'s ``case`` for training seed
    ``seed``, simulated offline at ``snr_db`` as the board plays it."""
    run = simulate(case_trials(case, seed, trials), snr_db)
    return run.events, run.truth


def truth_onsets(ev: np.ndarray, truth: np.ndarray) -> list[tuple[int, int, str]]:
    """(decision window start µs, contact, what it is) of each onset the receiver's rule
    (skinhil/receiver/onset.py, default parameters) finds: ``touch-down`` at most
    :data:`MATCH_US` after a contact's touch-down (each contact of a suite case touches
    once), ``release`` within :data:`RELEASE_US` of a contact's last touching tick, else
    ``other`` (noise, or activity within a touch; contact -1)."""
    touching = truth[truth["nodes"] > 0]
    contacts = np.unique(touching["contact"])
    downs = sorted((int(touching["t_us"][touching["contact"] == c].min()), int(c))
                   for c in contacts)
    ups = [(int(touching["t_us"][touching["contact"] == c].max()), int(c)) for c in contacts]
    n_steps = int(truth["t_us"].max() // STEP_US) + 1
    counts = np.bincount(ev["t"] // STEP_US, minlength=n_steps)[:n_steps]
    params = OnsetParams()
    lookback = int(round(params.lookback_s * 1e6))
    out = []
    for step in OnsetDetector(STEP_US * 1e-6, params).process(counts):
        t = step * STEP_US
        before = [(d, c) for d, c in downs if d <= t]
        up = [c for u, c in ups if RELEASE_US[0] <= t - u <= RELEASE_US[1]]
        if before and t - before[-1][0] <= MATCH_US:
            out.append((t - lookback, before[-1][1], "touch-down"))
        elif up:
            out.append((t - lookback, up[0], "release"))
        else:
            out.append((t - lookback, -1, "other"))
    return out


def detected_touches(ev: np.ndarray, truth: np.ndarray) -> list[tuple[int, int]]:
    """(decision window start µs, contact) of each onset the receiver answers as a touch
    (its rule, skinhil/receiver/onset.py with default parameters, and the touch-down/release
    rule, skinhil/receiver/touch_kind.py) found at most :data:`MATCH_US` after a contact's
    touch-down (:func:`truth_onsets`)."""
    mask = in_layer((6, 6))
    return [(t0, c) for t0, c, what in truth_onsets(ev, truth) if what == "touch-down"
            and touch_kind(ev["t"], ev["addr"], t0, mask) == TOUCH_DOWN]
