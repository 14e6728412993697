"""`--lsl` without pylsl, and bad `--view` / `--psp-sensors`: one `skinhil: error:` line
that says what to do, exit status 2, before any link is opened."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _skinhil(*args: str, pre: str = "") -> subprocess.CompletedProcess[str]:
    code = f"{pre}import sys; from skinhil.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=120, check=False, env={**os.environ, "PYTHONPATH": str(REPO)})


def _one_error_line(res: subprocess.CompletedProcess[str]) -> str:
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skinhil: error:"), res.stderr
    return lines[0]


HIDE_PYLSL = "import sys; sys.modules['pylsl'] = None; "
"""An import blocker: ``import pylsl`` fails as if it were not installed."""


@pytest.mark.parametrize("command", [["listen", "--port", "/dev/null/none", "--model",
                                      "none.npz"], ["demo", "--model", "none.npz"]])
def test_lsl_without_pylsl_names_the_pip_install(command: list[str]) -> None:
    line = _one_error_line(_skinhil(*command, "--lsl", pre=HIDE_PYLSL))
    assert 'pip install "skinhil[lsl]"' in line


def test_view_refuses_a_bad_address() -> None:
    line = _one_error_line(_skinhil("listen", "--port", "/dev/null/none", "--model",
                                    "none.npz", "--view", "localhost:http"))
    assert "[HOST:]PORT" in line and "8050" in line


def test_psp_sensors_outside_the_skin_are_refused() -> None:
    line = _one_error_line(_skinhil("listen", "--port", "/dev/null/none", "--model",
                                    "none.npz", "--view", "0", "--psp-sensors", "0,338"))
    assert "sensors 0..337" in line


def test_nwb_metadata_without_an_nwb_output_is_refused(tmp_path: Path) -> None:
    line = _one_error_line(_skinhil("simulate", "--out", str(tmp_path / "run.npz"),
                                    "--experimenter", "Doe, Jane"))
    assert "--experimenter" in line and ".nwb" in line
    assert not (tmp_path / "run.npz").exists()
