"""How far the paper's linear model departs from the true spring lengths, against the strain:
the measurement behind the default skin's strain bound (skinhil/model/skin.py, STRAIN_BOUND).

For each amplitude factor (mass, stiffness and damping of the paper regime multiplied
together: the same modes and linear forces, every displacement divided by the factor) it runs
the paper's five inputs and the nine Figure 4 conditions on the geometric mechanics with the
length readout and on the linear mechanics with the axial readout (the paper's eqs. 2-8), and
prints the largest strain of the geometric runs and the largest force gap between the two,
relative to the largest force of each run:

    python benchmarks/strain_bound.py
    python benchmarks/strain_bound.py --smoke     # one factor, two stimuli, 50 ms
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from skinhil.model.skin import SkinModel, SkinParams  # noqa: E402
from skinhil.model.stimuli import direction_conditions, paper_stimuli  # noqa: E402
from skinhil.model.strain import strain_summary  # noqa: E402

FACTORS = (1.0, 3.0, 10.0, 30.0, 100.0, 300.0)
"""Amplitude factors on the paper regime (100: the default skin)."""
DURATION_S = 0.3
"""Simulated time per stimulus (s): the indentation and 50 ms after it."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke", action="store_true", help="one factor, two stimuli, 50 ms")
    args = ap.parse_args()
    stimuli = paper_stimuli() + direction_conditions()
    factors, duration = FACTORS, DURATION_S
    if args.smoke:
        stimuli, factors, duration = stimuli[:2], (100.0,), 0.05
    paper = SkinParams.at_amplitude("paper")
    print("factor  max strain  largest gap (linear/axial vs geometric/length, of the peak)")
    for factor in factors:
        p = paper.scaled(factor)
        geo = SkinModel(replace(p, mechanics="geometric", readout="length")
                        ).simulate_many(stimuli, duration)
        lin = SkinModel(replace(p, mechanics="linear", readout="axial")
                        ).simulate_many(stimuli, duration)
        gaps = [np.abs(g - q).max() / np.abs(g).max() for g, q in zip(geo, lin, strict=True)]
        print(f"{factor:6g}  {100 * strain_summary(geo, p).max:9.3g} %  {100 * max(gaps):9.3g} %")


if __name__ == "__main__":
    main()
