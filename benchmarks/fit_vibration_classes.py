"""Fits the reference VIBRATION decoder's classes (skinhil/receiver/task_decoders.py): per
vibration frequency, the mean of the decoder's features over the calibration touches, and each
feature's within-class spread, on calibration runs of the suite's ``vibration`` case on
training seeds (task_calibration.py).

The touches are found by the receiver's own onset rule (skinhil/receiver/onset.py, default
parameters) and called touch-downs by its skinhil/receiver/touch_kind.py, each read from its
decision window's start (3 ms before the detection) for VIBRATION_WINDOW_S, and labelled with
the frequency of the contact touching then (an onset more than 50 ms after the latest
touch-down is a release or noise: left out). fit_reference_answerers.py stores the fit with
its provenance:

    python benchmarks/fit_vibration_classes.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_vibration_classes.py --smoke     # one seed, four trials only
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from task_calibration import REPO, calibration_args, case_trials, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.dataset import simulate  # noqa: E402
from skinhil.receiver.task_decoders import (  # noqa: E402
    VIBRATION_CLASSES_HZ,
    VIBRATION_WINDOW_S,
    vibration_features,
)


def touches(snr_db: float, seed: int, trials: int | None) -> tuple[np.ndarray, np.ndarray]:
    """The features and the frequency (Hz) of each detected touch of one calibration run."""
    played = case_trials("vibration", seed, trials)
    contacts = played.scenario.scene.contacts  # type: ignore[union-attr]
    hz = np.array([c.trajectory.vibration_frequency_hz for c in contacts])
    run = simulate(played, snr_db)
    ev = run.events
    window = int(round(VIBRATION_WINDOW_S * 1e6))
    x, y = [], []
    for start, contact in detected_touches(ev, run.truth):
        w = ev[(ev["t"] >= start) & (ev["t"] < start + window)]
        x.append(vibration_features(w["t"], w["addr"]))
        y.append(hz[contact])
    return np.array(x).reshape(-1, 1 + len(VIBRATION_CLASSES_HZ)), np.array(y)


def fit(snr_db: float, seeds: list[int], trials: int | None = None) -> dict[str, Any] | None:
    """Per class of VIBRATION_CLASSES_HZ the features' ``means``, their within-class
    ``spread``, and how many ``touches`` were ``classed_right`` on this fit; None when some
    class had no touch."""
    runs = [touches(snr_db, s, trials) for s in seeds]
    x = np.vstack([r[0] for r in runs])
    y = np.concatenate([r[1] for r in runs])
    if any(not np.any(y == f) for f in VIBRATION_CLASSES_HZ):
        return None
    means = np.array([x[y == f].mean(axis=0) for f in VIBRATION_CLASSES_HZ])
    spread = (x - means[[VIBRATION_CLASSES_HZ.index(f) for f in y]]).std(axis=0)
    z = (x[:, None, :] - means[None]) / spread
    fitted = np.asarray(VIBRATION_CLASSES_HZ)[np.argmin((z ** 2).sum(axis=2), axis=1)]
    return {"classes_hz": list(VIBRATION_CLASSES_HZ),
            "means": [[round(float(v), 2) for v in row] for row in means],
            "spread": [round(float(v), 2) for v in spread], "touches": len(y),
            "classed_right": round(float(np.mean(fitted == y)), 3)}


def main() -> None:
    snr_db, seeds, trials = calibration_args(__doc__ or "")
    f = fit(snr_db, seeds, trials)
    if f is None:
        played = "every" if trials is None else f"the first {trials}"
        print(f"some class had no touch in {played} trials of {len(seeds)} seed(s): too few "
              "to fit every class")
        if trials is None:
            raise SystemExit(1)
        return
    print(f"{f['touches']} touches detected over {len(seeds)} seeds; means {f['means']}; "
          f"spread {f['spread']}; classed right on this fit: {f['classed_right']:.0%}")


if __name__ == "__main__":
    main()
