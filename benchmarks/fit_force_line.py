"""Fits the reference FORCE decoder's line (skinhil/receiver/task_decoders.py): the normal
force at the end of each detected touch's decision window against the count of the touch's
spikes (task_decoders.touch_spikes), by
least squares, on calibration runs of examples/scenarios/task_force.toml.

Each calibration run is ``skinhil simulate`` (offline, no link) at the given SNR and one of the
seeds; the touches are found by the receiver's own onset rule (skinhil/receiver/onset.py,
default parameters) and called touch-downs by its skinhil/receiver/touch_kind.py, an onset more
than 50 ms after the latest touch-down (a release, or noise) left out, and their windows are
the receiver's (from 3 ms before the detection, 50 ms long):

    python benchmarks/fit_force_line.py --snr-db 10 --seeds 1,2,3,4,5,6
    python benchmarks/fit_force_line.py --smoke     # one seed, the first 8 s only
"""

from __future__ import annotations

import sys

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.receiver.task_decoders import sensor_xy_mm, touch_spikes  # noqa: E402

WINDOW_US = 50_000


def touches(snr_db: float, seed: int, duration: list[str]) -> tuple[list[int], list[float]]:
    """Per detected touch of one calibration run: the count of its spikes (the decoder's
    touch_spikes of its window) and its contact's normal force (N) at the window's end."""
    ev, truth = calibration_run("force", snr_db, seed, duration)
    touching = truth[truth["nodes"] > 0]
    xy_mm = sensor_xy_mm((6, 6))
    spikes, force = [], []
    for t0, contact in detected_touches(ev, truth):
        at = touching[(touching["contact"] == contact) & (touching["t_us"] <= t0 + WINDOW_US)]
        w = ev[(ev["t"] >= t0) & (ev["t"] < t0 + WINDOW_US)]
        spikes.append(touch_spikes(w["t"], w["addr"], t0, xy_mm)[1])
        force.append(float(at["normal_n"][-1]))
    return spikes, force


def main() -> None:
    snr_db, seeds, duration = calibration_args(__doc__ or "", "1,2,3,4,5,6")
    spikes: list[int] = []
    force: list[float] = []
    for seed in seeds:
        s, f = touches(snr_db, seed, duration)
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
