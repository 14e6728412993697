"""CPU time of another process, read from ``/proc`` (Linux), for the benchmarks."""

from __future__ import annotations

import os
import time


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
