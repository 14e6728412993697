"""Fits the reference FORCE decoder's line (skinhil/receiver/task_decoders.py): the normal
force at the end of each detected touch's decision window against the count of the touch's
spikes (task_decoders.touch_spikes), by least squares, on calibration runs of the suite's
``force`` case on training seeds (task_calibration.py).

The touches are found by the receiver's own onset rule (skinhil/receiver/onset.py, default
parameters) and called touch-downs by its skinhil/receiver/touch_kind.py, an onset more than
50 ms after the latest touch-down (a release, or noise) left out, and their windows are the
receiver's (from 3 ms before the detection, 50 ms long). fit_reference_answerers.py stores
the fit with its provenance:

    python benchmarks/fit_force_line.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_force_line.py --smoke     # one seed, four trials only
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.receiver.task_decoders import sensor_xy_mm, touch_spikes  # noqa: E402

WINDOW_US = 50_000
TOLERANCE_N = 0.05
"""A force answered this near (N) the truth is right (the board's tolerance)."""


def touches(snr_db: float, seed: int, trials: int | None) -> tuple[list[int], list[float]]:
    """Per detected touch of one calibration run: the count of its spikes (the decoder's
    touch_spikes of its window) and its contact's normal force (N) at the window's end."""
    ev, truth = calibration_run("force", snr_db, seed, trials)
    touching = truth[truth["nodes"] > 0]
    xy_mm = sensor_xy_mm((6, 6))
    spikes, force = [], []
    for t0, contact in detected_touches(ev, truth):
        at = touching[(touching["contact"] == contact) & (touching["t_us"] <= t0 + WINDOW_US)]
        w = ev[(ev["t"] >= t0) & (ev["t"] < t0 + WINDOW_US)]
        spikes.append(touch_spikes(w["t"], w["addr"], t0, xy_mm)[1])
        force.append(float(at["normal_n"][-1]))
    return spikes, force


def fit(snr_db: float, seeds: list[int], trials: int | None = None) -> dict[str, Any]:
    """The line's ``offset_n`` and ``n_per_spike`` over the detected touches of ``seeds``,
    with how well it fits (``touches``, ``correlation``, ``median_error_n``,
    ``within_tolerance``)."""
    spikes: list[int] = []
    force: list[float] = []
    for seed in seeds:
        s, f = touches(snr_db, seed, trials)
        spikes += s
        force += f
    x, y = np.array(spikes, dtype=float), np.array(force)
    if len(x) < 2:
        raise SystemExit(f"{len(x)} touches: too few to fit a line")
    slope, offset = np.polyfit(x, y, 1)
    err = np.abs(slope * x + offset - y)
    return {"offset_n": round(float(offset), 4), "n_per_spike": round(float(slope), 4),
            "touches": len(x), "correlation": round(float(np.corrcoef(x, y)[0, 1]), 3),
            "median_error_n": round(float(np.median(err)), 4),
            "within_tolerance": round(float(np.mean(err <= TOLERANCE_N)), 3)}


def main() -> None:
    snr_db, seeds, trials = calibration_args(__doc__ or "")
    f = fit(snr_db, seeds, trials)
    print(f"{f['touches']} touches over {len(seeds)} seeds; N = {f['n_per_spike']:.4f} * "
          f"spikes + {f['offset_n']:.4f}; correlation {f['correlation']:.2f}; median |error| "
          f"{f['median_error_n']:.3f} N; {f['within_tolerance']:.0%} within {TOLERANCE_N} N")


if __name__ == "__main__":
    main()
