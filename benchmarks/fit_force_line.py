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


TOLERANCE_N = 0.05
"""A force answered this near (N) the truth is right (the board's tolerance)."""


def touches(snr_db: float, seed: int,
            duration: list[str]) -> tuple[list[int], list[float], list[float], list[float]]:
    """Per detected touch of one calibration run: the count of its spikes (the decoder's
    touch_spikes of its window), its contact's normal force (N) at the window's end and its
    press's held force (N, its largest); and the held force of every press of the run."""
    ev, truth = calibration_run("force", snr_db, seed, duration)
    touching = truth[truth["nodes"] > 0]
    held = {int(c): float(touching["normal_n"][touching["contact"] == c].max())
            for c in np.unique(touching["contact"])}
    xy_mm = sensor_xy_mm((6, 6))
    spikes, force, level = [], [], []
    for t0, contact in detected_touches(ev, truth):
        at = touching[(touching["contact"] == contact) & (touching["t_us"] <= t0 + WINDOW_US)]
        w = ev[(ev["t"] >= t0) & (ev["t"] < t0 + WINDOW_US)]
        spikes.append(touch_spikes(w["t"], w["addr"], t0, xy_mm)[1])
        force.append(float(at["normal_n"][-1]))
        level.append(held[contact])
    return spikes, force, level, list(held.values())


def main() -> None:
    snr_db, seeds, duration = calibration_args(__doc__ or "", "1,2,3,4,5,6")
    spikes: list[int] = []
    force: list[float] = []
    level: list[float] = []
    presses: list[float] = []
    for seed in seeds:
        s, f, lv, p = touches(snr_db, seed, duration)
        spikes += s
        force += f
        level += lv
        presses += p
    x, y = np.array(spikes, dtype=float), np.array(force)
    if len(x) < 2:
        raise SystemExit(f"{len(x)} touches: too few to fit a line")
    slope, offset = np.polyfit(x, y, 1)
    err = np.abs(slope * x + offset - y)
    print(f"{len(x)} touches over seeds {','.join(map(str, seeds))}; "
          f"N = {slope:.4f} * spikes + {offset:.4f}; "
          f"correlation {np.corrcoef(x, y)[0, 1]:.2f}; median |error| {np.median(err):.3f} N; "
          f"{np.mean(err <= TOLERANCE_N):.0%} within {TOLERANCE_N} N")
    held, pressed = np.round(level, 1), np.round(presses, 1)
    for n in np.unique(pressed):
        at = held == n
        found = f"  presses of {n:.1f} N: {at.sum()} of {np.sum(pressed == n)} found"
        if not at.any():
            print(found)
            continue
        sd = f"{x[at].std():.1f}" if at.sum() > 1 else "-"
        print(f"{found}, {np.mean(err[at] <= TOLERANCE_N):.0%} within {TOLERANCE_N} N, "
              f"spikes {x[at].mean():.1f} ± {sd}")

if __name__ == "__main__":
    main()
