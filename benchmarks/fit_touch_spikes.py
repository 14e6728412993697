"""Chooses the reference decoders' touch spikes (skinhil/receiver/task_decoders.py, TOUCH_SPIKES_S
and TOUCH_RADIUS_MM): the window's first so many ms, within so many mm of their trimmed
centroid, whichever pair locates most detected touches within 0.5 mm of the contact's centroid,
on calibration runs of the suite's localisation case on training seeds (task_calibration.py).

Each calibration run is simulated offline at the given SNR for one of the seeds; the touches
are found by the receiver's own onset rule (skinhil/receiver/onset.py, default parameters) and
called touch-downs by its skinhil/receiver/touch_kind.py, an onset more than 50 ms after the
latest touch-down left out, and their windows are the receiver's (from 3 ms before the
detection, 50 ms long):

    python benchmarks/fit_touch_spikes.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_touch_spikes.py --smoke     # one seed, four trials only
"""

from __future__ import annotations

import sys

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.receiver.task_decoders import (  # noqa: E402
    TOUCH_RADIUS_MM,
    TOUCH_SPIKES_S,
    sensor_xy_mm,
    touch_spikes,
)

WINDOW_US = 50_000
SPIKES_S = (0.01, 0.015, 0.02, 0.03, 0.05)
"""The lengths (s) tried."""
RADII_MM = (1.0, 1.5, 2.0, 2.5)
"""The radii (mm) tried."""
RIGHT_MM = 0.5
"""A touch located this near (mm) the contact's centroid is right (the board's tolerance)."""


def main() -> None:
    snr_db, seeds, duration = calibration_args(__doc__ or "")
    xy_mm = sensor_xy_mm((6, 6))
    windows = []
    for seed in seeds:
        ev, truth = calibration_run("localisation", snr_db, seed, duration)
        touching = truth[truth["nodes"] > 0]
        for t0, contact in detected_touches(ev, truth):
            at = touching[(touching["contact"] == contact) & (touching["t_us"] <= t0 + WINDOW_US)]
            w = ev[(ev["t"] >= t0) & (ev["t"] < t0 + WINDOW_US)]
            windows.append((w, t0, float(at["x_mm"][-1]), float(at["y_mm"][-1])))
    print(f"{len(windows)} touches detected over seeds {','.join(map(str, seeds))}")
    if not windows:
        return
    best = (-1.0, 0.0, 0.0)
    for spikes_s in SPIKES_S:
        for radius_mm in RADII_MM:
            err = np.array([np.hypot(*np.subtract(
                touch_spikes(w["t"], w["addr"], t0, xy_mm, spikes_s, radius_mm)[0], (x, y)))
                for w, t0, x, y in windows])
            right = float(np.mean(err <= RIGHT_MM))
            print(f"{spikes_s * 1e3:4.0f} ms {radius_mm:.1f} mm: {right:.0%} within "
                  f"{RIGHT_MM} mm, median {np.median(err):.2f} mm")
            best = max(best, (right, spikes_s, radius_mm))
    print(f"best: TOUCH_SPIKES_S = {best[1]:g}, TOUCH_RADIUS_MM = {best[2]:g}; in "
          f"task_decoders.py: {TOUCH_SPIKES_S:g}, {TOUCH_RADIUS_MM:g}")


if __name__ == "__main__":
    main()
