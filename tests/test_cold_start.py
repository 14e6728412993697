"""A cold kernel cache is announced at once: ``serve`` and ``listen`` on an empty
``NUMBA_CACHE_DIR`` say within 2 s of launch (once their input is checked) that they
compile, for about how long, and where the kernels go; SIGTERM then stops them cleanly
(status 143, no traceback).

Most of those 2 s is importing the command (``listen`` imports scikit-learn), which a busy
machine slows down; so the bound is the larger of 2 s and the command's own start-up, its
``--help`` timed just before, plus :data:`AFTER_START_UP_S`: nothing slow (a compile, a model
trained) may come before the notice."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from harness.hostile_models import write_good
from harness.serve import RUN_DIR, serve_env

NOTICE_WITHIN_S = 2.0
AFTER_START_UP_S = 0.5
"""Seconds the notice may come after the command's start-up (module docstring)."""


def _start_up_s(command: str) -> float:
    """Wall time (s) of ``skinhil COMMAND --help`` here and now: the interpreter and the
    command's imports, nothing else."""
    t0 = time.monotonic()
    subprocess.run([sys.executable, "-m", "skinhil", command, "--help"], cwd=RUN_DIR,
                   env=serve_env(), stdin=subprocess.DEVNULL, capture_output=True, check=True,
                   timeout=60)
    return time.monotonic() - t0


@pytest.mark.parametrize("command", ["serve", "listen"])
def test_cold_cache_announced_within_2_s(command: str, tmp_path: Path) -> None:
    argv = ["--port", "loop://", "--duration", "30"]
    if command == "listen":
        argv += ["--model", str(write_good(tmp_path / "m.npz", n_channels=338))]
    env = {**serve_env(), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    bound = max(NOTICE_WITHIN_S, _start_up_s(command) + AFTER_START_UP_S)
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "skinhil", command, *argv], cwd=RUN_DIR,
                            env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        elapsed = time.monotonic() - t0
        assert "compiling" in line and str(tmp_path / "numba") in line, line
        assert "s before it starts" in line and "skinhil compile" in line, line
        assert elapsed < bound, (elapsed, bound, line)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 143, err
        assert "Traceback" not in err, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def test_an_unknown_command_is_refused_without_importing_the_commands() -> None:
    """``skinhil NOSUCH`` says which commands there are and exits 2 without importing any
    command's module (scikit-learn's import among them)."""
    probe = ("import sys\nfrom skinhil.cli import main\ntry:\n    main(['nosuch'])\n"
             "except SystemExit as exc:\n    rc = exc.code\n"
             "print(rc, sorted(m for m in ('sklearn', 'skinhil.cli.listen', 'skinhil.cli.serve') "
             "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], cwd=RUN_DIR, env=serve_env(),
                         stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
    assert out.stdout.split("\n")[0] == "2 []", out.stdout + out.stderr
    assert "invalid choice: 'nosuch'" in out.stderr and "serve" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
