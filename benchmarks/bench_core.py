"""Speed of the simulation core: real-time factor of one skin, and 450 trials.

Run: ``python benchmarks/bench_core.py [--smoke] [--results-dir DIR]`` (pinned to one core;
``--smoke``: tiny runs, a few seconds, to check the script runs: its figures mean little).
Reports
- the real-time factor of one skin (mechanics + 338 neurons + noise at 10 dB) stepped as the
  board steps it, in 1 ms blocks of 0.1 ms steps, for both mechanics (targets ≥ 20x linear,
  ≥ 5x geometric);
- the wall time to simulate 450 trials (9 conditions x 50 repetitions) of 0.5 s with spikes
  at 10 dB (target ≤ 10 s);
- ``SkinModel.simulate`` of paper stimulus A (0.5 s on the 0.1 ms grid) against scipy's
  ``solve_ivp`` RK45 at its default tolerances on the same equations (``x' = A x + B u(t)``,
  the stimulus profile evaluated at any t, output on the same 0.1 ms grid) (target ≥ 2x);
- the same 450 trials kept as events (:func:`skinhil.model.trials.simulate_trial_events`): wall
  time, events, and the peak of the memory allocated while they run (tracemalloc: numpy's
  and Python's allocations; target ≤ 250 MB), beside the dense raster's.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tracemalloc

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe, load_average, pin_one_core  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

pin_one_core()

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from skinhil import (  # noqa: E402
    SkinModel,
    SkinParams,
    direction_conditions,
    paper_stimuli,
    random_schedule,
)
from skinhil.model.mechanics.linear import free_dofs, state_space  # noqa: E402
from skinhil.model.sensor import SkinSensor  # noqa: E402
from skinhil.model.trials import simulate_trial_events, simulate_trials  # noqa: E402

REPEATS = 3
"""Each figure is the best of this many runs: the machine is a shared VM whose speed varies."""
SIM_S = 5.0
"""Simulated seconds per real-time-factor run."""
TRIAL_REPS, TRIAL_S = 50, 0.5
"""Repetitions per condition and seconds per trial of the trial runs (450 trials x 0.5 s)."""


def real_time_factor(mechanics: str) -> float:
    """Simulated seconds per wall second, stepping 1 ms blocks of 0.1 ms under a schedule."""
    sim_s = SIM_S
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
        raster = simulate_trials(direction_conditions(), TRIAL_REPS, duration_s=TRIAL_S,
                                 snr_db=10.0, seed=0)
        walls.append(time.perf_counter() - t0)
        assert raster.shape == (9, TRIAL_REPS, int(round(TRIAL_S / 1e-4)), 338)
        del raster
    return min(walls)


def simulate_vs_solve_ivp() -> tuple[float, float, float]:
    """Best wall s of ``SkinModel.simulate`` and of solve_ivp RK45 (default tolerances) on
    paper stimulus A over 0.5 s, output on the 0.1 ms grid; and their largest difference
    relative to the peak force."""
    # the state space solve_ivp integrates, read out as its C y (the axial projection)
    model = SkinModel(SkinParams(mechanics="linear", readout="axial"))
    stim = paper_stimuli()[0]
    dt, n = 1e-4, int(round(TRIAL_S / 1e-4))
    model.simulate(stim, 0.01, dt)  # compile
    p = model.params
    a, b = state_space(model.mesh, p.mass_kg, p.stiffness_n_per_m, p.damping_n_s_per_m,
                       p.tension_n)
    dofs = free_dofs(model.mesh)
    push = b @ stim.peak_forces_n.ravel()[dofs]
    sense = model.stepper(dt).cy  # type: ignore[attr-defined]
    t_eval = np.arange(n) * dt

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return a @ y + push * float(stim.profile(t))

    ours_s, ref_s = [], []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        ours = model.simulate(stim, n * dt, dt)
        ours_s.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, t_eval[-1]), np.zeros(a.shape[0]), method="RK45",
                        t_eval=t_eval)
        ref = np.asarray(sense @ sol.y[:dofs.size]).T
        ref_s.append(time.perf_counter() - t0)
    return min(ours_s), min(ref_s), float(np.abs(ours - ref).max() / np.abs(ours).max())


def trial_events_memory() -> tuple[float, int, float, float]:
    """450 trials x 0.5 s at 10 dB as events: best wall s, events, and the peak MB allocated
    (tracemalloc) by the events run and by the dense raster run."""
    simulate_trial_events(direction_conditions()[:1], 1, duration_s=0.01, snr_db=10.0)
    walls = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        ev = simulate_trial_events(direction_conditions(), TRIAL_REPS, duration_s=TRIAL_S,
                                   snr_db=10.0, seed=0)
        walls.append(time.perf_counter() - t0)
        n_events = sum(len(e) for trial in ev for e in trial)
        del ev
    peaks = []
    for fn in (simulate_trial_events, simulate_trials):
        tracemalloc.start()
        out = fn(direction_conditions(), TRIAL_REPS, duration_s=TRIAL_S, snr_db=10.0, seed=0)
        peaks.append(tracemalloc.get_traced_memory()[1] / 1e6)
        tracemalloc.stop()
        del out
    return min(walls), n_events, peaks[0], peaks[1]


def main() -> None:
    global REPEATS, SIM_S, TRIAL_REPS, TRIAL_S
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke", action="store_true",
                    help="tiny runs (one of each, 0.05 s, 9 x 2 trials): the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        REPEATS, SIM_S, TRIAL_REPS, TRIAL_S = 1, 0.05, 2, 0.05
    print(describe())
    print(f"best of {REPEATS} runs each; {load_average()}", flush=True)
    lin = real_time_factor("linear")
    print(f"real-time factor, linear mechanics:    {lin:6.1f}x  (target >= 20x)", flush=True)
    geo = real_time_factor("geometric")
    print(f"real-time factor, geometric mechanics: {geo:6.1f}x  (target >= 5x)", flush=True)
    wall = trials_wall_s()
    print(f"{9 * TRIAL_REPS} trials x {TRIAL_S:g} s at dt 0.1 ms with spikes: {wall:5.2f} s  "
          "(target <= 10 s for 450 x 0.5 s)", flush=True)
    ours, ref, err = simulate_vs_solve_ivp()
    print(f"SkinModel.simulate, paper stimulus A, {TRIAL_S:g} s on the 0.1 ms grid: "
          f"{1e3 * ours:6.1f} ms;"
          f" solve_ivp RK45 (default tolerances, same equations and grid): {1e3 * ref:6.1f} ms;"
          f" {ref / ours:5.1f}x faster (target >= 2x); largest difference {err:.1e} of the peak"
          " force (RK45's own tolerance)", flush=True)
    ev_wall, n_ev, ev_mb, raster_mb = trial_events_memory()
    print(f"{9 * TRIAL_REPS} trials x {TRIAL_S:g} s kept as events: {ev_wall:5.2f} s, "
          f"{n_ev} events; peak memory allocated {ev_mb:6.1f} MB (target <= 250 MB; "
          f"tracemalloc), dense raster {raster_mb:6.1f} MB")
    print(load_average())
    trials = f"{9 * TRIAL_REPS} trials x {TRIAL_S:g} s"
    publish(args, "core", "Simulation core: real-time factor, trials, memory", [
        figure("real-time factor, linear mechanics", round(lin, 1), "x real time", "≥ 20"),
        figure("real-time factor, geometric mechanics", round(geo, 1), "x real time", "≥ 5"),
        figure(f"{trials} with spikes at 10 dB", round(wall, 2), "s",
               "≤ 10 for 450 x 0.5 s"),
        figure(f"SkinModel.simulate, stimulus A, {TRIAL_S:g} s", round(1e3 * ours, 1), "ms"),
        figure("solve_ivp RK45 over SkinModel.simulate", round(ref / ours, 1), "x faster",
               "≥ 2"),
        figure("largest difference to RK45", float(f"{err:.2g}"), "of the peak force"),
        figure(f"{trials} kept as events", round(ev_wall, 2), "s"),
        figure(f"{trials} kept as events: events", n_ev, "events"),
        figure(f"{trials} kept as events: peak memory allocated", round(ev_mb, 1), "MB",
               "≤ 250"),
        figure(f"{trials} as a dense raster: peak memory allocated", round(raster_mb, 1),
               "MB")])


if __name__ == "__main__":
    main()
