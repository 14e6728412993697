"""Benchmark results as JSON: one file per benchmark in ``benchmarks/results/``, holding the
machine, the load, the command, the date and the figures; the docs' benchmarks page is
rendered from these files (``docs/_ext/benchmark_results.py``), so no figure is typed by hand.
The record's fields are the schema ``benchmark-result`` (``skinhil/schemas/``).

Where a result goes (:func:`destination`): ``--results-dir DIR``, else the folder named by
the environment variable ``SKINHIL_BENCH_RESULTS``, else ``benchmarks/results/``; a
``--smoke`` run (whose figures mean nothing) writes only into a folder named by one of the
first two, never into ``benchmarks/results/``; ``--no-save`` writes nothing.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
from typing import Any

from machine import cpu_model

RESULTS_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
"""The results the docs' benchmarks page is built from."""
RESULTS_ENV = "SKINHIL_BENCH_RESULTS"
"""Environment variable naming the folder results are written into instead."""


def figure(name: str, value: float | int | str, unit: str, target: str = "") -> dict[str, Any]:
    """One measured figure: what it is, its value, its unit (a count's unit names what is
    counted) and the target it is held to ("" where none is set)."""
    if not unit:
        raise ValueError(f"figure {name!r} has no unit: give one (a count names what it counts)")
    return {"name": name, "value": value, "unit": unit, "target": target}


def machine() -> dict[str, Any]:
    """The machine a result was measured on: CPU model, cores, OS, Python and key packages."""
    cpu = cpu_model()
    import numba
    import numpy

    return {"cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(),
            "python": platform.python_version(), "numpy": numpy.__version__,
            "numba": numba.__version__}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options every writing benchmark takes: ``--results-dir`` and ``--no-save``."""
    parser.add_argument("--results-dir", metavar="DIR",
                        help=f"write the result file into DIR (default: ${RESULTS_ENV}, else "
                             "benchmarks/results/; a --smoke run writes only into one of the "
                             "first two)")
    parser.add_argument("--no-save", action="store_true", help="print only; write no result")


def destination(args: argparse.Namespace) -> str | None:
    """The folder this run's result goes into, or None when it writes none."""
    if getattr(args, "no_save", False):
        return None
    chosen = getattr(args, "results_dir", None) or os.environ.get(RESULTS_ENV) or None
    if chosen is None and getattr(args, "smoke", False):
        return None
    return chosen or RESULTS_DIR


def record(benchmark: str, title: str, figures: list[dict[str, Any]],
           smoke: bool = False) -> dict[str, Any]:
    """The result record of this run; the load averages are taken when it is called (the
    run's end)."""
    return {
        "benchmark": benchmark,
        "title": title,
        "command": " ".join(["python"] + sys.argv),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "machine": machine(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "smoke": smoke,
        "figures": figures,
    }


def save(benchmark: str, title: str, figures: list[dict[str, Any]],
         directory: str = RESULTS_DIR, smoke: bool = False) -> str:
    """Write ``<directory>/<benchmark>.json`` (replacing an older result of the same
    benchmark) and return its path."""
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"{benchmark}.json")
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(record(benchmark, title, figures, smoke), fh, indent=2, ensure_ascii=False)
        fh.write("\n")
    return path


def publish(args: argparse.Namespace, benchmark: str, title: str,
            figures: list[dict[str, Any]]) -> str | None:
    """Save this run's figures where :func:`destination` says, print the path, return it
    (None when the run writes none: no destination, or no figure measured, which leaves an
    older result in place)."""
    directory = destination(args)
    if directory is None:
        return None
    if not figures:
        print(f"no figure measured: {benchmark}'s result is not written")
        return None
    path = save(benchmark, title, figures, directory, smoke=bool(getattr(args, "smoke", False)))
    print("written:", path)
    return path
