"""Every script in ``benchmarks/`` runs in its smoke mode and prints its figures, so none rots;
each benchmark writes its result record (``benchmarks/results.py``) into the folder
``SKINHIL_BENCH_RESULTS`` names, valid against the schema ``benchmark-result``, and none
writes into ``benchmarks/results/``.

A script is a ``benchmarks/*.py`` with a ``if __name__ == "__main__":`` block (the helpers it
imports, such as ``machine.py``, have none); each one takes ``--smoke``: tiny sizes, a
second or two of board time, the same code paths. A new script without a smoke mode fails
here by name. The scripts run side by side, ``WORKERS`` at a time, as subprocesses started
when the first test asks (most of their time is waiting: interpreter start-up, a board's
real-time run), each with a results folder of its own.
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import pytest
from harness.serve import REPO, RUN_DIR, serve_env

from skinhil.schemas import validate

BENCHMARKS = REPO / "benchmarks"
WORKERS = 4
"""Scripts run at once (2 cores: most of a smoke run is start-up and waiting)."""
TIMEOUT_S = 300.0
"""Longest a smoke run may take (a loaded machine, a cold kernel cache)."""
DESCRIPTION = re.compile(r"^(machine|python|command|load average):")
"""Lines of ``benchmarks/machine.py``'s description: not figures."""
RESULTS_ENV = "SKINHIL_BENCH_RESULTS"
"""The folder a run writes its result records into (``benchmarks/results.py``)."""
RESULTS = BENCHMARKS / "results"
"""The committed results the docs' benchmarks page is built from."""
WRITES_NO_RESULT = {
    "contact_figures.py": "draws the docs' contact figures: no machine-dependent figure",
    "strain_bound.py": "a model measurement: the same on every machine",
    "task_calibration.py": "the fits' shared calibration runs",
}
"""Scripts whose figures are not benchmark figures a reader compares across machines (the
``fit_*`` scripts write fits, not figures): why each writes no result record."""


def scripts() -> list[Path]:
    """The benchmark scripts (files with a ``__main__`` block), by name."""
    return sorted(p for p in BENCHMARKS.glob("*.py")
                  if '__name__ == "__main__"' in p.read_text(encoding="utf-8"))


def writes_results(name: str) -> bool:
    """The script is a benchmark that writes its figures as a result record."""
    return name not in WRITES_NO_RESULT and not name.startswith("fit_")


def _run(path: Path, results: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(path), "--smoke"], cwd=RUN_DIR,
                          env={**serve_env(), RESULTS_ENV: str(results)},
                          capture_output=True, text=True, timeout=TIMEOUT_S,
                          stdin=subprocess.DEVNULL)


def _committed() -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in RESULTS.glob("*.json")}


@pytest.fixture(scope="module")
def results_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder per script (by its stem) for the records its smoke run writes."""
    return tmp_path_factory.mktemp("bench-results")


@pytest.fixture(scope="module")
def smoke_runs(results_root: Path
               ) -> Iterator[dict[str, Future[subprocess.CompletedProcess[str]]]]:
    """Every script with a smoke mode started (``WORKERS`` at a time), by file name; when
    they have all ended, the committed results are as they were."""
    before = _committed()
    with ThreadPoolExecutor(WORKERS) as pool:
        yield {path.name: pool.submit(_run, path, results_root / path.stem)
               for path in scripts() if "--smoke" in path.read_text(encoding="utf-8")}
    assert _committed() == before, "a --smoke run wrote into benchmarks/results/"


def test_the_scripts_are_found() -> None:
    names = {p.name for p in scripts()}
    assert {"bench_size.py", "bench_udp.py", "bench_live_hand.py", "bench_gamers.py"} <= names
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


@pytest.mark.parametrize("name", [p.name for p in scripts() if writes_results(p.name)])
def test_benchmark_smoke_mode_writes_its_result_record(
        name: str, smoke_runs: dict[str, Future[subprocess.CompletedProcess[str]]],
        results_root: Path) -> None:
    """The record is valid, marked a smoke run, its figures those of this script, every
    one with a unit; a script that measures several configurations writes one record each."""
    assert name in smoke_runs, f"benchmarks/{name} has no smoke mode"
    res = smoke_runs[name].result()
    assert res.returncode == 0, res.stderr[-3000:]
    folder = results_root / Path(name).stem
    paths = sorted(folder.glob("*.json"))
    assert paths, (f"benchmarks/{name} --smoke wrote no result into ${RESULTS_ENV}: save its "
                   "figures with results.publish (or list it in WRITES_NO_RESULT, saying why)")
    for path in paths:
        record = json.loads(path.read_text(encoding="utf-8"))
        validate("benchmark-result", record, str(path))
        assert path.name == f"{record['benchmark']}.json"
        assert record["smoke"] is True
        assert Path(record["command"].split()[1]).name == name
        assert "--smoke" in record["command"].split()
        assert f"written: {path}" in res.stdout


def test_the_committed_results_are_valid_and_not_smoke_runs() -> None:
    """What the docs' benchmarks page is built from: full runs, each file named as its
    benchmark."""
    paths = sorted(RESULTS.glob("*.json"))
    assert paths
    for path in paths:
        record = json.loads(path.read_text(encoding="utf-8"))
        validate("benchmark-result", record, str(path))
        assert path.name == f"{record['benchmark']}.json"
        assert record["smoke"] is False, f"{path} is a smoke run's: its figures mean nothing"


def test_a_smoke_run_writes_only_into_a_folder_it_is_given(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--smoke`` without ``--results-dir`` or ``SKINHIL_BENCH_RESULTS`` writes no record
    (a full run writes into benchmarks/results/); given a folder, it writes one there."""
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    results = importlib.import_module("results")
    monkeypatch.delenv(RESULTS_ENV, raising=False)
    ap = argparse.ArgumentParser()
    ap.add_argument("--smoke", action="store_true")
    results.add_arguments(ap)
    assert results.destination(ap.parse_args(["--smoke"])) is None
    assert results.destination(ap.parse_args(["--no-save"])) is None
    assert results.destination(ap.parse_args([])) == str(RESULTS)
    path = results.publish(ap.parse_args(["--smoke", "--results-dir", str(tmp_path)]), "check",
                           "A check", [results.figure("a", 1.5, "s", "≤ 2")])
    assert path == str(tmp_path / "check.json")
    record = json.loads((tmp_path / "check.json").read_text(encoding="utf-8"))
    validate("benchmark-result", record, path)
    assert record["smoke"] is True and record["figures"][0]["target"] == "≤ 2"
    monkeypatch.setenv(RESULTS_ENV, str(tmp_path / "env"))
    assert results.destination(ap.parse_args(["--smoke"])) == str(tmp_path / "env")
    with pytest.raises(ValueError, match="no unit"):
        results.figure("a", 1, "")
