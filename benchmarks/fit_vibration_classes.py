"""Fits the reference VIBRATION decoder's classes (skinhil/receiver/task_decoders.py): per
vibration frequency, the mean of the decoder's features over the calibration touches, and each
feature's within-class spread, on calibration runs of examples/scenarios/task_vibration.toml.

Each calibration run is ``skinhil simulate`` (offline, no link) at the given SNR and one of the
seeds; the touches are found by the receiver's own onset rule (skinhil/receiver/onset.py,
default parameters) and called touch-downs by its skinhil/receiver/touch_kind.py, each read
from its decision window's start (3 ms before the detection) for VIBRATION_WINDOW_S, and
labelled with the frequency of the contact touching then (an onset more than 50 ms after the
latest touch-down is a release or noise: left out):

    python benchmarks/fit_vibration_classes.py --snr-db 10 --seeds 1,2,3,4,5,6
    python benchmarks/fit_vibration_classes.py --smoke     # one seed, the first 8 s only
"""

from __future__ import annotations

import sys

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.receiver.task_decoders import (  # noqa: E402
    VIBRATION_CLASSES_HZ,
    VIBRATION_WINDOW_S,
    vibration_class_hz,
    vibration_features,
)
from skinhil.world.scenario_file import load_scenario  # noqa: E402

SCENARIO = REPO / "examples" / "scenarios" / "task_vibration.toml"


def touches(snr_db: float, seed: int, duration: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The features and the frequency (Hz) of each detected touch of one calibration run."""
    contacts = load_scenario(SCENARIO).scene.contacts  # type: ignore[union-attr]
    hz = np.array([c.trajectory.vibration_frequency_hz for c in contacts])
    ev, truth = calibration_run("vibration", snr_db, seed, duration)
    window = int(round(VIBRATION_WINDOW_S * 1e6))
    x, y = [], []
    for start, contact in detected_touches(ev, truth):
        w = ev[(ev["t"] >= start) & (ev["t"] < start + window)]
        x.append(vibration_features(w["t"], w["addr"]))
        y.append(hz[contact])
    return np.array(x).reshape(-1, 1 + len(VIBRATION_CLASSES_HZ)), np.array(y)


def main() -> None:
    snr_db, seeds, duration = calibration_args(__doc__ or "", "1,2,3,4,5,6")
    runs = [touches(snr_db, s, duration) for s in seeds]
    x = np.vstack([r[0] for r in runs])
    y = np.concatenate([r[1] for r in runs])
    print(f"{len(y)} touches detected over seeds {','.join(map(str, seeds))}")
    present = [f for f in VIBRATION_CLASSES_HZ if np.any(y == f)]
    if len(present) < len(VIBRATION_CLASSES_HZ):
        print(f"touches of only {present} Hz: too few to fit every class")
        if duration:  # --smoke: the script ran
            return
        raise SystemExit(1)
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
    print(f"classed right by the constants in task_decoders.py: {np.mean(current == y):.0%}")


if __name__ == "__main__":
    main()
