"""Measures the reference receiver's touch-down/release rule (skinhil/receiver/touch_kind.py) and
chooses its burst length KIND_S: on calibration runs of the suite's cases on training seeds
(task_calibration.py), what the rule calls each onset the receiver's onset rule finds, by what
the truth says it is (a touch-down, a release, other: noise or activity within a touch), for
burst lengths of 15, 25 and 40 ms.

Each calibration run is simulated offline at the given SNR for one of the seeds; the onsets are
the receiver's (skinhil/receiver/onset.py, default parameters), their windows start 3 ms before
the detection, as the receiver's. The length chosen is the one that calls the most touch-downs
touch-downs and releases releases (their mean share):

    python benchmarks/fit_touch_kind.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_touch_kind.py --smoke     # the force case, one seed, four trials only
"""

from __future__ import annotations

import sys
from collections import Counter

from task_calibration import REPO, calibration_args, calibration_run, truth_onsets

sys.path.insert(0, str(REPO))

from skinhil.receiver.touch_kind import (  # noqa: E402
    KIND_S,
    RELEASE,
    TOUCH_DOWN,
    in_layer,
    touch_kind,
)

TASKS = ("localisation", "force", "slip", "vibration")
KINDS_S = (0.015, 0.025, 0.04)
"""The burst lengths (s) tried."""
WHAT = ("touch-down", "release", "other")
CALLED = (TOUCH_DOWN, RELEASE, None)


def main() -> None:
    snr_db, seeds, duration = calibration_args(__doc__ or "")
    tasks = ("force",) if duration else TASKS
    mask = in_layer((6, 6))
    tally: dict[float, Counter[tuple[str, str, str | None]]] = {k: Counter() for k in KINDS_S}
    touches: Counter[str] = Counter()
    for task in tasks:
        for seed in seeds:
            ev, truth = calibration_run(task, snr_db, seed, duration)
            touching = truth[truth["nodes"] > 0]
            touches[task] += len(set(touching["contact"].tolist()))
            for t0, _, what in truth_onsets(ev, truth):
                for kind_s in KINDS_S:
                    called = touch_kind(ev["t"], ev["addr"], t0, mask, kind_s)
                    tally[kind_s][(task, what, called)] += 1
    print(f"seeds {','.join(map(str, seeds))}, {snr_db:g} dB: onsets at a touch-down / at a "
          "release / other, called touch-down, release, neither")
    best = (-1.0, 0.0)
    for kind_s in KINDS_S:
        t = tally[kind_s]
        print(f"KIND_S {kind_s * 1e3:.0f} ms:")
        for task in tasks:
            cells = [f"{what} " + "/".join(str(t[(task, what, c)]) for c in CALLED)
                     for what in WHAT]
            print(f"  {task:12s} {touches[task]} touches; " + "; ".join(cells))
        downs = sum(t[(task, "touch-down", c)] for task in tasks for c in CALLED)
        ups = sum(t[(task, "release", c)] for task in tasks for c in CALLED)
        down_ok = sum(t[(task, "touch-down", TOUCH_DOWN)] for task in tasks) / max(downs, 1)
        up_ok = sum(t[(task, "release", RELEASE)] for task in tasks) / max(ups, 1)
        up_as_down = sum(t[(task, "release", TOUCH_DOWN)] for task in tasks) / max(ups, 1)
        print(f"  all: touch-downs called touch-down {down_ok:.0%} of {downs}; releases "
              f"called release {up_ok:.0%}, mistaken for a touch-down {up_as_down:.0%} of {ups}")
        best = max(best, ((down_ok + up_ok) / 2, kind_s))
    print(f"best: KIND_S = {best[1]:g}; in touch_kind.py: {KIND_S:g}")


if __name__ == "__main__":
    main()
