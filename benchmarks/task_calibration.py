"""What the reference task decoders' fits share (fit_force_line.py, fit_vibration_classes.py,
fit_slip_channels.py): their command line, the calibration runs (``skinhil simulate`` of a task
scenario, offline, no link) and the touches the receiver's own onset rule finds in them."""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from skinhil.receiver.onset import OnsetDetector  # noqa: E402
from skinhil.receiver.params import OnsetParams  # noqa: E402

STEP_US = 100
"""The receiver's step (µs) the onsets are found on."""
MATCH_US = 50_000
"""An onset this long (µs) at most after a touch-down is that touch's (the others, releases
and noise, are left out)."""
SMOKE_DURATION_S = 8.0
"""--smoke: board time (s) simulated, the scenario's first trials."""


def calibration_args(doc: str, seeds: str) -> tuple[float, list[int], list[str]]:
    """The command line of a fit: its SNR (dB), seeds and ``simulate``'s duration options."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seeds", default=seeds, help="the calibration runs' board seeds")
    ap.add_argument("--smoke", action="store_true",
                    help=f"one seed, the first {SMOKE_DURATION_S:g} s of board time only (a "
                         "check that the script runs, not a fit to use)")
    args = ap.parse_args()
    chosen = [int(s) for s in args.seeds.split(",") if s]
    if args.smoke:
        return args.snr_db, chosen[:1], ["--duration", str(SMOKE_DURATION_S)]
    return args.snr_db, chosen, []


def calibration_run(task: str, snr_db: float, seed: int,
                    duration: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The events and the contact truth of ``examples/scenarios/task_<task>.toml`` simulated
    at ``snr_db`` with ``seed``."""
    scenario = REPO / "examples" / "scenarios" / f"task_{task}.toml"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cal.npz"
        subprocess.run([sys.executable, "-m", "skinhil", "simulate", "--schedule",
                        str(scenario), "--out", str(out), "--no-progress", "--no-forces",
                        "--snr-db", str(snr_db), "--seed", str(seed), *duration],
                       check=True, capture_output=True)
        z = np.load(out)
        return z["events"], z["truth"]


def detected_touches(ev: np.ndarray, truth: np.ndarray) -> list[tuple[int, int]]:
    """(decision window start µs, contact) of each onset the receiver's rule
    (skinhil/receiver/onset.py, default parameters) finds at most :data:`MATCH_US` after a
    contact's touch-down (each contact of a task scenario touches once)."""
    touching = truth[truth["nodes"] > 0]
    downs = sorted((int(touching["t_us"][touching["contact"] == c].min()), int(c))
                   for c in np.unique(touching["contact"]))
    n_steps = int(truth["t_us"].max() // STEP_US) + 1
    counts = np.bincount(ev["t"] // STEP_US, minlength=n_steps)[:n_steps]
    params = OnsetParams()
    lookback = int(round(params.lookback_s * 1e6))
    out = []
    for step in OnsetDetector(STEP_US * 1e-6, params).process(counts):
        before = [(t, c) for t, c in downs if t <= step * STEP_US]
        if before and step * STEP_US - before[-1][0] <= MATCH_US:
            out.append((step * STEP_US - lookback, before[-1][1]))
    return out
