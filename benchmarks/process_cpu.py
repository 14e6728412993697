"""CPU time of another process, read from ``/proc`` (Linux), for the benchmarks."""

from __future__ import annotations

import os
import time
from collections.abc import Callable


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` (all its threads)."""
    with open(f"/proc/{pid}/stat", encoding="ascii") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def settle(pid: int, timeout_s: float = 120.0) -> None:
    """Wait until process ``pid`` is idle (started up: < 20 ms CPU in 0.5 s)."""
    end = time.monotonic() + timeout_s
    last = cpu_s(pid)
    while time.monotonic() < end:
        time.sleep(0.5)
        now = cpu_s(pid)
        if now - last < 0.02:
            return
        last = now


def cpu_while(pid: int, wait: Callable[[], int], after_s: float) -> tuple[int, float, float]:
    """Run ``wait()`` (a board's run: its exit status) and ``after_s`` s more; return that
    status, the CPU seconds process ``pid`` used meanwhile and the wall seconds it took."""
    c0, t0 = cpu_s(pid), time.monotonic()
    rc = wait()
    time.sleep(after_s)
    return rc, cpu_s(pid) - c0, time.monotonic() - t0
