"""Fits the reference SLIP decoder's channels (skinhil/receiver/task_decoders.py): the
channels that are near silent while a held contact sticks and fire once it slips, on
calibration runs of the suite's ``slip`` case on training seeds (task_calibration.py).

Per slide, from the run's truth: its stick spikes, 50..120 ms after the touch-down, and its
slip spikes, 20..90 ms after the slip onset (the first tick of gross slip once the touch has
lasted 20 ms, the board's rule). A channel is a slip channel when, on average over the
slides, it fires at most STICK_MAX spikes in the stick window and at least RISE_MIN more in
the slip window. fit_reference_answerers.py stores the fit with its provenance:

    python benchmarks/fit_slip_channels.py --snr-db 10 --seeds 1-20
    python benchmarks/fit_slip_channels.py --smoke     # one seed, four trials only
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from task_calibration import REPO, calibration_args, calibration_run

sys.path.insert(0, str(REPO))

from skinhil.world.truth import SLIP_STATES  # noqa: E402

STICK_US = (50_000, 120_000)
SLIP_US = (20_000, 90_000)
SETTLE_US = 20_000
"""Gross slip in a touch's first this long (µs) is its touch-down (the board's rule)."""
STICK_MAX = 0.5
RISE_MIN = 0.5
N_CHANNELS = 338


def slides(snr_db: float, seed: int, trials: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Per slide of one calibration run: the spikes per channel while it sticks and once it
    slips (two (n_slides, N_CHANNELS) arrays)."""
    ev, truth = calibration_run("slip", snr_db, seed, trials)

    def counts(a: int, b: int) -> np.ndarray:
        sel = ev["addr"][(ev["t"] >= a) & (ev["t"] < b)].astype(np.int64)
        return np.bincount(sel, minlength=N_CHANNELS)[:N_CHANNELS]

    stick, slip = [], []
    gross = SLIP_STATES.index("gross")
    for c in np.unique(truth["contact"]):
        rows = truth[(truth["contact"] == c) & (truth["nodes"] > 0)]
        if not len(rows):
            continue
        down = int(rows["t_us"][0])
        slipping = rows["t_us"][(rows["slip"] == gross) & (rows["t_us"] >= down + SETTLE_US)]
        if not len(slipping):
            continue
        onset = int(slipping[0])
        stick.append(counts(down + STICK_US[0], down + STICK_US[1]))
        slip.append(counts(onset + SLIP_US[0], onset + SLIP_US[1]))
    return (np.array(stick, float).reshape(-1, N_CHANNELS),
            np.array(slip, float).reshape(-1, N_CHANNELS))


def fit(snr_db: float, seeds: list[int], trials: int | None = None) -> dict[str, Any]:
    """The slip ``channels`` over the slides of ``seeds``, with their mean spikes per slide
    while sticking and once slipping (per 70 ms)."""
    runs = [slides(snr_db, s, trials) for s in seeds]
    stick = np.vstack([r[0] for r in runs])
    slip = np.vstack([r[1] for r in runs])
    if not len(stick):
        raise SystemExit("no slide slipped: nothing to fit")
    a, b = stick.mean(axis=0), slip.mean(axis=0)
    chosen = np.flatnonzero((a <= STICK_MAX) & (b - a >= RISE_MIN))
    return {"channels": [int(c) for c in chosen], "slides": len(stick),
            "stick_spikes": round(float(a[chosen].sum()), 2),
            "slip_spikes": round(float(b[chosen].sum()), 2)}


def main() -> None:
    snr_db, seeds, trials = calibration_args(__doc__ or "")
    f = fit(snr_db, seeds, trials)
    print(f"{f['slides']} slides over {len(seeds)} seeds; {len(f['channels'])} slip channels: "
          f"{f['stick_spikes']:.1f} spikes while sticking, {f['slip_spikes']:.1f} once "
          f"slipping (per 70 ms, mean per slide): {f['channels']}")


if __name__ == "__main__":
    main()
