"""Measures the reference SLIP decoder's latency (skinhil/receiver/task_decoders.py,
``slip_time_us`` from each touch the receiver detects) from each slip onset of the board's
rule (the first tick of gross slip once the touch has lasted 20 ms), on calibration runs of
the suite's ``slip`` case on training seeds (task_calibration.py), and prints the slip
response window of the board's score (skinhil/tasks/slip.py ``SLIP_WINDOW_US``): the
latencies' QUANTILE (the largest: the window must not cut a detection of the reference)
plus the live path's margin (LIVE_MARGIN_US), rounded up to ROUND_US.

    python benchmarks/fit_slip_window.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_slip_window.py --smoke     # one seed, four trials only
"""

from __future__ import annotations

import math
import sys

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run, detected_touches

sys.path.insert(0, str(REPO))

from skinhil.receiver.task_decoders import slip_time_us  # noqa: E402
from skinhil.scoring.tasks import SETTLE_US  # noqa: E402
from skinhil.tasks.slip import SLIP_WINDOW_US  # noqa: E402
from skinhil.world.truth import SLIP_STATES  # noqa: E402

QUANTILE = 1.0
"""The share of the reference's detections the window keeps."""
LIVE_MARGIN_US = 50_000
"""The live receiver answers later than this offline replay: from the spikes as they arrive
(in batches), from the touch window of its live onset, and a tick or two over the link;
tests/test_suite_gamers.py's reference run checks that the window keeps its detections."""
ROUND_US = 50_000
"""The window is rounded up to this (µs)."""


def latencies_us(snr_db: float, seed: int, trials: int | None) -> list[int]:
    """Per slide of one calibration run that the reference detects: slip onset → detection
    (µs); a detection before the onset is negative (a false alarm on the board)."""
    ev, truth = calibration_run("slip", snr_db, seed, trials)
    gross = SLIP_STATES.index("gross")
    out = []
    for t0, c in detected_touches(ev, truth):
        rows = truth[(truth["contact"] == c) & (truth["nodes"] > 0)]
        down = int(rows["t_us"][0])
        slipping = rows["t_us"][(rows["slip"] == gross) & (rows["t_us"] >= down + SETTLE_US)]
        found = slip_time_us(ev["t"], ev["addr"], t0)
        if len(slipping) and found is not None:
            out.append(int(found) - int(slipping[0]))
    return out


def main() -> None:
    snr_db, seeds, trials = calibration_args(__doc__ or "")
    lat = np.array([v for s in seeds for v in latencies_us(snr_db, s, trials)], dtype=float)
    if not len(lat):
        raise SystemExit("the reference detected no slip: nothing to fit")
    q = float(np.quantile(lat, QUANTILE))
    window = int(math.ceil((q + LIVE_MARGIN_US) / ROUND_US) * ROUND_US)
    p50, p90 = np.percentile(lat, [50, 90]) * 1e-3
    print(f"{len(lat)} detected slides over {len(seeds)} seeds; latency p50 {p50:.1f} ms, "
          f"p90 {p90:.1f} ms, p{QUANTILE * 100:g} {q * 1e-3:.1f} ms, early "
          f"{int((lat < 0).sum())}; slip window {window / 1e3:g} ms "
          f"(the board's SLIP_WINDOW_US: {SLIP_WINDOW_US / 1e3:g} ms)")


if __name__ == "__main__":
    main()
