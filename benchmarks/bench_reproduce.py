"""Cost of the reproduction: one sweep grid point on one core, and the full run.

Run: ``python benchmarks/bench_reproduce.py [--out DIR] [--skip-full] [--smoke]
[--results-dir DIR]``
(``--smoke``: two linear and one geometric grid point, no full run, to check the script
runs). Reports
- the time of one K x C grid point (5 paper stimuli, 0.5 s, both phases' measures) on one
  core, median of 20 points of the default grid, for the linear mechanics (target ≤ 50 ms)
  and, for information, the geometric one (median of 5);
- the wall time of the full ``skinhil reproduce`` (the 2 x 2 x 2 design: both mechanics,
  both readouts, both amplitudes; 11 x 11 K x C sweeps, two 6 x 5 tension slices at the
  paper's amplitude, 12 feature sets decoded at 7 SNRs with 5 x 5-fold cross-validation, the
  paper preset's search) on all cores.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

from skinhil.analysis.sweep import SweepSpec, evaluate_point  # noqa: E402
from skinhil.reproduce import ReproduceConfig, reproduce  # noqa: E402


def point_cost_s(mechanics: str, n: int) -> float:
    """Median seconds per grid point over ``n`` points spread over the default grid."""
    points = list(SweepSpec.log_grid(20, 20, mechanics=mechanics).points())  # type: ignore[arg-type]
    step = max(1, len(points) // n)
    chosen = points[::step][:n]
    evaluate_point(chosen[0])  # compile and warm caches
    times = []
    for p in chosen:
        t0 = time.perf_counter()
        evaluate_point(p)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="output directory of the full run (default: temporary)")
    parser.add_argument("--skip-full", action="store_true", help="only the grid-point cost")
    parser.add_argument("--smoke", action="store_true",
                        help="3 grid points and no full run: the script runs")
    add_arguments(parser)
    args = parser.parse_args()
    print(describe())
    n_linear, n_geometric = (2, 1) if args.smoke else (20, 5)
    linear_ms = point_cost_s("linear", n_linear) * 1e3
    print(f"grid point, linear, one core: {linear_ms:.1f} ms (target <= 50 ms)")
    geometric_ms = point_cost_s("geometric", n_geometric) * 1e3
    print(f"grid point, geometric, one core: {geometric_ms:.0f} ms")
    publish(args, "reproduce_grid_point", "Reproduction: one sweep grid point on one core", [
        figure(f"grid point, linear, median of {n_linear}", round(linear_ms, 1), "ms", "≤ 50"),
        figure(f"grid point, geometric, median of {n_geometric}", round(geometric_ms),
               "ms")])
    if args.skip_full or args.smoke:
        return 0
    out = args.out or tempfile.mkdtemp(prefix="skinhil-reproduce-")
    t0 = time.perf_counter()
    outcome = reproduce(out, ReproduceConfig(progress=False))
    total = time.perf_counter() - t0
    print(f"full reproduce: {total:.1f} s wall on {os.cpu_count()} cores; report "
          f"{outcome.report}")
    figures = [figure(f"full reproduce, wall on {os.cpu_count()} cores", round(total, 1), "s",
                      "≤ 900")]
    for r in outcome.results:
        print(f"  {r.label}: " + ", ".join(f"{k} {v:.1f} s" for k, v in r.seconds.items()))
        figures += [figure(f"{r.label}: {k}", round(v, 1), "s") for k, v in r.seconds.items()]
    publish(args, "reproduce_full", "Reproduction: the full skinhil reproduce", figures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
