"""The code is clean: ruff over everything, mypy over the three packages."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _run(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=600)


def test_ruff() -> None:
    res = _run([sys.executable, "-m", "ruff", "check", "skinhil", "firmware_sim", "protocols",
                "tests", "benchmarks"])
    assert res.returncode == 0, res.stdout + res.stderr


def test_mypy() -> None:
    res = _run([sys.executable, "-m", "mypy", "skinhil", "firmware_sim", "protocols"])
    assert res.returncode == 0, res.stdout + res.stderr
