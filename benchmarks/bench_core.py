"""Speed of the simulation core: real-time factor of one skin, and 450 trials.

Run: ``python benchmarks/bench_core.py`` (pinned to one core). Reports
- the real-time factor of one skin (mechanics + 338 neurons + noise at 10 dB) stepped as the
  board steps it, in 1 ms blocks of 0.1 ms steps, for both mechanics (targets ≥ 20x linear,
  ≥ 5x geometric);
- the wall time to simulate 450 trials (9 conditions x 50 repetitions) of 0.5 s with spikes
  at 10 dB (target ≤ 10 s).
"""

from __future__ import annotations

import os
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe, load_average, pin_one_core  # noqa: E402

pin_one_core()

from skinhil import SkinModel, SkinParams, direction_conditions, random_schedule  # noqa: E402
from skinhil.sensor import SkinSensor  # noqa: E402
from skinhil.trials import simulate_trials  # noqa: E402

REPEATS = 3
"""Each figure is the best of this many runs: the machine is a shared VM whose speed varies."""


def real_time_factor(mechanics: str, sim_s: float = 5.0) -> float:
    """Simulated seconds per wall second, stepping 1 ms blocks of 0.1 ms under a schedule."""
    dt = 1e-4
    sensor = SkinSensor(SkinModel(SkinParams(mechanics=mechanics)), dt, snr_db=10.0, seed=0)
    schedule = random_schedule(direction_conditions(), 40, rest_s=0.25, seed=0)
    sensor.advance_schedule(schedule, 10)  # compile
    best = 0.0
    for _ in range(REPEATS):
        sensor.reset()
        n_blocks = int(round(sim_s / 1e-3))
        t0 = time.perf_counter()
        for _ in range(n_blocks):
            sensor.advance_schedule(schedule, 10)
        best = max(best, sim_s / (time.perf_counter() - t0))
    return best


def trials_wall_s() -> float:
    """Wall seconds for 9 conditions x 50 repetitions x 0.5 s at 10 dB, with spikes."""
    simulate_trials(direction_conditions()[:1], 1, duration_s=0.01, snr_db=10.0)  # compile
    walls = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        raster = simulate_trials(direction_conditions(), 50, duration_s=0.5, snr_db=10.0, seed=0)
        walls.append(time.perf_counter() - t0)
        assert raster.shape == (9, 50, 5000, 338)
        del raster
    return min(walls)


def main() -> None:
    print(describe())
    print(f"best of {REPEATS} runs each; {load_average()}", flush=True)
    lin = real_time_factor("linear")
    print(f"real-time factor, linear mechanics:    {lin:6.1f}x  (target >= 20x)", flush=True)
    geo = real_time_factor("geometric")
    print(f"real-time factor, geometric mechanics: {geo:6.1f}x  (target >= 5x)", flush=True)
    wall = trials_wall_s()
    print(f"450 trials x 0.5 s at dt 0.1 ms with spikes: {wall:5.2f} s  (target <= 10 s)")
    print(load_average())


if __name__ == "__main__":
    main()
