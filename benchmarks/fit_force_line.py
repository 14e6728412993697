"""Fits the reference FORCE decoder's line (skinhil/receiver/task_decoders.py): the normal
force at the end of each detected touch's decision window against the window's spikes, by
least squares, on calibration runs of examples/scenarios/task_force.toml.

Each calibration run is ``skinhil simulate`` (offline, no link) at the given SNR and one of the
seeds, its
onsets found by the receiver's own rule (skinhil/receiver/onset.py, default parameters) and
its windows as the receiver's (from 3 ms before the detection, 50 ms long); an onset more than
50 ms after the latest touch-down (a release, or noise) is left out:

    python benchmarks/fit_force_line.py --snr-db 10 --seeds 1,2,3,4,5,6
    python benchmarks/fit_force_line.py --smoke     # the first 2 s of board time only
"""

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

WINDOW_US = 50_000
STEP_US = 100
MATCH_US = 50_000
"""An onset this long (µs) at most after a touch-down is that touch's (the others, releases
and noise, are left out)."""
SMOKE_DURATION_S = 2.0
"""--smoke: board time (s) simulated, the scenario's first presses."""


def touches(snr_db: float, seed: int, duration: list[str]) -> tuple[list[int], list[float]]:
    """Per detected touch of one calibration run: its window's spikes and the normal force
    (N) at the window's end."""
    scenario = REPO / "examples" / "scenarios" / "task_force.toml"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cal.npz"
        subprocess.run([sys.executable, "-m", "skinhil", "simulate", "--schedule", str(scenario),
                        "--out", str(out), "--no-progress", "--no-forces", "--snr-db",
                        str(snr_db), "--seed", str(seed), *duration], check=True,
                       capture_output=True)
        z = np.load(out)
        ev, truth = z["events"], z["truth"]
    n_steps = int(truth["t_us"].max() // STEP_US) + 1
    counts = np.bincount(ev["t"] // STEP_US, minlength=n_steps)[:n_steps]
    params = OnsetParams()
    lookback = int(round(params.lookback_s * 1e6))
    onsets = [s * STEP_US - lookback for s in OnsetDetector(STEP_US * 1e-6, params).process(counts)]
    touching = truth[truth["nodes"] > 0]
    downs = np.array(sorted(int(touching["t_us"][touching["contact"] == c].min())
                            for c in np.unique(touching["contact"])))
    spikes, force = [], []
    for t0 in onsets:
        k = np.searchsorted(downs, t0 + lookback, side="right") - 1
        if k < 0 or t0 + lookback - downs[k] > MATCH_US:
            continue  # a release or a noise onset: no touch-down to fit
        at = touching[(touching["t_us"] >= t0) & (touching["t_us"] <= t0 + WINDOW_US)]
        spikes.append(int(((ev["t"] >= t0) & (ev["t"] < t0 + WINDOW_US)).sum()))
        force.append(float(at["normal_n"][-1]))
    return spikes, force


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seeds", default="1,2,3,4,5,6")
    ap.add_argument("--smoke", action="store_true",
                    help=f"one seed, the first {SMOKE_DURATION_S:g} s of board time only (a "
                         "check that the script runs, not a fit to use)")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",") if s]
    duration = ["--duration", str(SMOKE_DURATION_S)] if args.smoke else []
    if args.smoke:
        seeds = seeds[:1]
    spikes: list[int] = []
    force: list[float] = []
    for seed in seeds:
        s, f = touches(args.snr_db, seed, duration)
        spikes += s
        force += f
    x, y = np.array(spikes, dtype=float), np.array(force)
    if len(x) < 2:
        raise SystemExit(f"{len(x)} touches: too few to fit a line")
    slope, offset = np.polyfit(x, y, 1)
    err = np.abs(slope * x + offset - y)
    print(f"{len(x)} touches over seeds {','.join(map(str, seeds))}; "
          f"N = {slope:.4f} * spikes + {offset:.4f}; "
          f"correlation {np.corrcoef(x, y)[0, 1]:.2f}; median |error| {np.median(err):.3f} N")


if __name__ == "__main__":
    main()
