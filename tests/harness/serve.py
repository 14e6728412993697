"""Run ``skinhil serve`` as a subprocess, as a user would, and collect its output: its
ready line and summary line (docs/process-output.md) are read by ``type``, never by text."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from skinhil.process_output import READY, SUMMARY, last_record

REPO = Path(__file__).resolve().parents[2]


def serve_env() -> dict[str, str]:
    """This environment with the repository under test on PYTHONPATH (after any others)."""
    paths = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(paths + [str(REPO)]),
            "PYTHONUNBUFFERED": "1"}


RUN_DIR = tempfile.gettempdir()
"""Working directory of the subprocesses (not the repository, so PYTHONPATH decides)."""


def realtime_args() -> list[str]:
    """``["--realtime"]`` where this process may use real-time scheduling (root or
    CAP_SYS_NICE), else ``[]``: timing assertions then hold on a loaded 2-core machine."""
    try:
        old = os.sched_getscheduler(0), os.sched_getparam(0)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
        os.sched_setscheduler(0, old[0], old[1])
    except (OSError, AttributeError):
        return []
    return ["--realtime"]


def serve_argv(*args: str) -> list[str]:
    """The command line of ``skinhil serve ARGS`` with this Python and this repository."""
    return [sys.executable, "-m", "skinhil", "serve", *args]


def run_serve(*args: str, timeout_s: float = 60.0) -> subprocess.CompletedProcess[str]:
    """Run serve to completion; stdout/stderr captured as text."""
    return subprocess.run(serve_argv(*args), cwd=RUN_DIR, env=serve_env(), text=True,
                          capture_output=True, timeout=timeout_s, stdin=subprocess.DEVNULL)


class ServeProcess:
    """A running ``skinhil serve --json ...`` (or another ``command``: ``listen``); its JSON
    lines and stderr are collected."""

    def __init__(self, *args: str, command: str = "serve") -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "skinhil", command, *args],
                                     cwd=RUN_DIR, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                                     text=True, env=serve_env())
        self.lines: list[dict[str, Any]] = []
        self.arrived: list[float] = []
        """Wall-clock time (``time.time()``) each of ``lines`` was read."""
        self.stderr_lines: list[str] = []
        self._threads = [threading.Thread(target=self._read_out, daemon=True),
                         threading.Thread(target=self._read_err, daemon=True)]
        for t in self._threads:
            t.start()

    def _read_out(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            try:
                item = json.loads(line)
            except json.JSONDecodeError:
                item = {"type": "text", "text": line}
            self.arrived.append(time.time())
            self.lines.append(item)

    def _read_err(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.stderr_lines.append(line)

    @property
    def exited(self) -> bool:
        return self.proc.poll() is not None

    def interrupt(self) -> None:
        self.proc.send_signal(signal.SIGINT)

    def wait(self, timeout_s: float = 30.0) -> int:
        try:
            rc = self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise
        for t in self._threads:
            t.join(timeout=2.0)
        return rc

    @property
    def stderr(self) -> str:
        return "".join(self.stderr_lines)

    def summary(self) -> dict[str, Any]:
        """The summary line (the last of its type)."""
        found = last_record(list(self.lines), SUMMARY)
        assert found is not None, f"no summary; stderr:\n{self.stderr}"
        return found

    def wait_ready(self, timeout_s: float = 120.0) -> dict[str, Any]:
        """The ready line, once it has come (``--json``): the link is open and the run
        starts. Fails if the process ends first or ``timeout_s`` passes."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            found = last_record(list(self.lines), READY)
            if found is not None:
                return found
            assert not self.exited, f"ended with no ready line; stderr:\n{self.stderr}"
            time.sleep(0.05)
        raise AssertionError(f"no ready line within {timeout_s:g} s; stderr:\n{self.stderr}")

    def start_wall_s(self) -> float:
        """When the board started on the wall clock (s since the epoch), from its status
        lines: the earliest of each line's arrival minus its board time (a line leaves a
        moment after its board time, so the earliest is the closest)."""
        starts = [at - x["board_time_s"] for x, at in zip(list(self.lines), list(self.arrived),
                                                          strict=False)
                  if x.get("type") == "status"]
        assert starts, f"no status line; stderr:\n{self.stderr}"
        return min(starts)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
