"""Every script in ``benchmarks/`` runs in its smoke mode and prints its figures, so none rots.

A script is a ``benchmarks/*.py`` with a ``if __name__ == "__main__":`` block (the helpers it
imports, such as ``machine.py``, have none); each one takes ``--smoke``: tiny sizes, a
second or two of board time, the same code paths. A new script without a smoke mode fails
here by name. The scripts run side by side, ``WORKERS`` at a time, as subprocesses started
when the first test asks (most of their time is waiting: interpreter start-up, a board's
real-time run).
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import pytest
from harness.serve import REPO, RUN_DIR, serve_env

BENCHMARKS = REPO / "benchmarks"
WORKERS = 4
"""Scripts run at once (2 cores: most of a smoke run is start-up and waiting)."""
TIMEOUT_S = 300.0
"""Longest a smoke run may take (a loaded machine, a cold kernel cache)."""
DESCRIPTION = re.compile(r"^(machine|python|command|load average):")
"""Lines of ``benchmarks/machine.py``'s description: not figures."""


def scripts() -> list[Path]:
    """The benchmark scripts (files with a ``__main__`` block), by name."""
    return sorted(p for p in BENCHMARKS.glob("*.py")
                  if '__name__ == "__main__"' in p.read_text(encoding="utf-8"))


def _run(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(path), "--smoke"], cwd=RUN_DIR, env=serve_env(),
                          capture_output=True, text=True, timeout=TIMEOUT_S,
                          stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def smoke_runs() -> Iterator[dict[str, Future[subprocess.CompletedProcess[str]]]]:
    """Every script with a smoke mode started (``WORKERS`` at a time), by file name."""
    with ThreadPoolExecutor(WORKERS) as pool:
        yield {path.name: pool.submit(_run, path) for path in scripts()
               if "--smoke" in path.read_text(encoding="utf-8")}


def test_the_scripts_are_found() -> None:
    names = {p.name for p in scripts()}
    assert {"bench_size.py", "bench_udp.py", "bench_live_hand.py"} <= names
    assert "machine.py" not in names  # a helper, not a script


@pytest.mark.parametrize("name", [p.name for p in scripts()])
def test_benchmark_smoke_mode_runs_and_prints_figures(
        name: str, smoke_runs: dict[str, Future[subprocess.CompletedProcess[str]]]) -> None:
    assert name in smoke_runs, (f"benchmarks/{name} has no smoke mode: give it a --smoke "
                                "option (tiny sizes, a few seconds)")
    res = smoke_runs[name].result()
    assert res.returncode == 0, f"benchmarks/{name} --smoke exited {res.returncode}:\n" \
                                f"{res.stdout[-2000:]}\n{res.stderr[-3000:]}"
    assert "Traceback" not in res.stderr, res.stderr[-3000:]
    figures = [line for line in res.stdout.splitlines()
               if re.search(r"\d", line) and not DESCRIPTION.match(line)]
    assert figures, f"benchmarks/{name} --smoke printed no figures:\n{res.stdout}"
