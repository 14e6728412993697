"""Benchmark results as JSON: one file per benchmark in ``benchmarks/results/``, holding the
machine, the command, the date and the figures; the docs' benchmarks page is rendered from
these files (``docs/_ext/benchmark_results.py``), so no figure is typed by hand."""

from __future__ import annotations

import datetime
import json
import os
import platform
import sys
from typing import Any

from machine import cpu_model

RESULTS_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")


def figure(name: str, value: float | int | str, unit: str = "", target: str = "") -> dict[str, Any]:
    """One measured figure: what it is, its value and unit, and the target it is held to."""
    return {"name": name, "value": value, "unit": unit, "target": target}


def machine() -> dict[str, Any]:
    """The machine a result was measured on: CPU model, cores, OS, Python and key packages."""
    cpu = cpu_model()
    import numba
    import numpy

    return {"cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(),
            "python": platform.python_version(), "numpy": numpy.__version__,
            "numba": numba.__version__}


def save(benchmark: str, title: str, figures: list[dict[str, Any]],
         directory: str = RESULTS_DIR) -> str:
    """Write ``<directory>/<benchmark>.json`` (replacing an older result of the same
    benchmark) and return its path; the load averages are taken when the run ends."""
    os.makedirs(directory, exist_ok=True)
    record = {
        "benchmark": benchmark,
        "title": title,
        "command": " ".join(["python"] + sys.argv),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "machine": machine(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "figures": figures,
    }
    path = os.path.join(directory, f"{benchmark}.json")
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(record, fh, indent=2, ensure_ascii=False)
        fh.write("\n")
    return path
