"""Fits the reference VIBRATION decoder's classes (skinhil/receiver/task_decoders.py): per
vibration frequency, the mean of the decoder's features over the calibration touches, and each
feature's within-class spread, on calibration runs of examples/scenarios/task_vibration.toml.

Each calibration run is ``skinhil simulate`` (offline, no link) at the given SNR and one of the
seeds; the touches are found by the receiver's own onset rule (skinhil/receiver/onset.py,
default parameters), each read from its decision window's start (3 ms before the detection)
for VIBRATION_WINDOW_S, and labelled with the frequency of the contact touching then (an onset
more than 50 ms after the latest touch-down is a release or noise: left out):

    python benchmarks/fit_vibration_classes.py --snr-db 10 --seeds 1,2,3,4,5,6
    python benchmarks/fit_vibration_classes.py --smoke     # one seed, the first 2 s only
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
from skinhil.receiver.task_decoders import (  # noqa: E402
    VIBRATION_CLASSES_HZ,
    VIBRATION_MEANS,
    VIBRATION_SPREAD,
    VIBRATION_WINDOW_S,
    vibration_class_hz,
    vibration_features,
)
from skinhil.world.scenario_file import load_scenario  # noqa: E402

STEP_US = 100
MATCH_US = 50_000
"""An onset this long (µs) at most after a touch-down is that touch's."""
SMOKE_DURATION_S = 2.0
SCENARIO = REPO / "examples" / "scenarios" / "task_vibration.toml"


def touches(snr_db: float, seed: int, duration: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The features and the frequency (Hz) of each detected touch of one calibration run."""
    contacts = load_scenario(SCENARIO).scene.contacts  # type: ignore[union-attr]
    hz = np.array([c.trajectory.vibration_frequency_hz for c in contacts])
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cal.npz"
        subprocess.run([sys.executable, "-m", "skinhil", "simulate", "--schedule",
                        str(SCENARIO), "--out", str(out), "--no-progress", "--no-forces",
                        "--snr-db", str(snr_db), "--seed", str(seed), *duration],
                       check=True, capture_output=True)
        z = np.load(out)
        ev, truth = z["events"], z["truth"]
    touching = truth[truth["nodes"] > 0]
    first = {int(c): int(touching["t_us"][touching["contact"] == c].min())
             for c in np.unique(touching["contact"])}
    downs = sorted((t, c) for c, t in first.items())
    n_steps = int(truth["t_us"].max() // STEP_US) + 1
    counts = np.bincount(ev["t"] // STEP_US, minlength=n_steps)[:n_steps]
    params = OnsetParams()
    lookback = int(round(params.lookback_s * 1e6))
    window = int(round(VIBRATION_WINDOW_S * 1e6))
    x, y = [], []
    for step in OnsetDetector(STEP_US * 1e-6, params).process(counts):
        start = step * STEP_US - lookback
        before = [(t, c) for t, c in downs if t <= step * STEP_US]
        if not before or step * STEP_US - before[-1][0] > MATCH_US:
            continue
        w = ev[(ev["t"] >= start) & (ev["t"] < start + window)]
        x.append(vibration_features(w["t"], w["addr"]))
        y.append(hz[before[-1][1]])
    return np.array(x).reshape(-1, 1 + len(VIBRATION_CLASSES_HZ)), np.array(y)


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
    runs = [touches(args.snr_db, s, duration) for s in seeds]
    x = np.vstack([r[0] for r in runs])
    y = np.concatenate([r[1] for r in runs])
    print(f"{len(y)} touches detected over seeds {','.join(map(str, seeds))}")
    present = [f for f in VIBRATION_CLASSES_HZ if np.any(y == f)]
    if len(present) < len(VIBRATION_CLASSES_HZ):
        raise SystemExit(f"touches of only {present} Hz: too few to fit every class")
    means = np.array([x[y == f].mean(axis=0) for f in VIBRATION_CLASSES_HZ])
    spread = (x - means[[VIBRATION_CLASSES_HZ.index(f) for f in y]]).std(axis=0)
    print("VIBRATION_MEANS = (")
    for row in means:
        print("    (" + ", ".join(f"{v:.2f}" for v in row) + "),")
    print(")")
    print("VIBRATION_SPREAD = (" + ", ".join(f"{v:.2f}" for v in spread) + ")")
    z = (x[:, None, :] - means[None]) / spread
    fitted = np.asarray(VIBRATION_CLASSES_HZ)[np.argmin((z ** 2).sum(axis=2), axis=1)]
    print(f"classed right on this fit: {np.mean(fitted == y):.0%}")
    current = np.array([vibration_class_hz(v) for v in x])
    print(f"classed right by the constants in task_decoders.py: {np.mean(current == y):.0%}"
          f" (its means {np.asarray(VIBRATION_MEANS).shape}, spread {len(VIBRATION_SPREAD)})")


if __name__ == "__main__":
    main()
