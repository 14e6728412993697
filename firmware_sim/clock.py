"""The board's fixed-step scheduler: publish ticks on the monotonic clock, without drift.

Tick ``k`` (k = 0, 1, ...) covers board time ``[k·tick_s, (k+1)·tick_s)``. Like firmware that
publishes what happened during the last period, its work is due at monotonic time
``t0 + (k+1)·tick_s``: deadlines are computed from ``t0`` and ``k``, never from the previous
wake-up, so simulated time tracks wall time with no drift. A late tick runs at once, and the
ticks behind it run back to back until the board has caught up.

Measured per tick: ``lateness`` = (start of the tick's work) − (its due time), in seconds;
a tick *misses its deadline* when its work ends after the next tick's due time
(``due + tick_s``). Misses are counted, never hidden.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import time
from pathlib import Path

import numpy as np

from skinhil.lateness import LatenessLog

log = logging.getLogger(__name__)

_PR_SET_TIMERSLACK = 29


def tighten_timer_slack(slack_ns: int = 1000) -> bool:
    """Ask Linux for ``slack_ns`` (ns) timer slack so sleeps end on time; False if unsupported."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return int(libc.prctl(_PR_SET_TIMERSLACK, int(slack_ns), 0, 0, 0)) == 0
    except (OSError, AttributeError):
        return False


def request_realtime(priority: int = 10) -> str | None:
    """Ask for the real-time FIFO scheduling class at ``priority`` (1..99), as firmware has
    the CPU to itself. Returns None on success, else why not (one line).

    Needs root or CAP_SYS_NICE (or ``ulimit -r``). The board sleeps between ticks, so it
    takes its share of one core first (``python benchmarks/bench_serve.py --realtime``
    measures it) and leaves the rest to everything else. Linux stops a real-time task that
    runs longer than its share of every second (``/proc/sys/kernel/sched_rt_runtime_us``, 95 %
    by default) for the rest of that second; :class:`TickClock` sleeps part of every tick so
    the board never reaches it.
    """
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(priority)))
    except (OSError, AttributeError, ValueError) as exc:
        return (f"cannot use real-time scheduling ({exc}); run as root, grant CAP_SYS_NICE "
                "or raise 'ulimit -r'")
    return None


def pin_to_cores(cores: tuple[int, ...]) -> str | None:
    """Run this process (and the threads it starts) on ``cores`` only, as firmware has its
    core to itself: no other program's thread takes turns on them unless it is pinned there
    too. Returns None on success, else why not (one line)."""
    try:  # every thread running now (Linux pins a thread; later ones inherit its cores)
        tasks = [int(t) for t in os.listdir("/proc/self/task")] or [0]
    except OSError:
        tasks = [0]
    try:
        for task in tasks:
            try:
                os.sched_setaffinity(task, set(cores))
            except ProcessLookupError:  # a thread that has just ended
                continue
    except (OSError, AttributeError, ValueError) as exc:
        return f"cannot run on cores {', '.join(map(str, cores))} ({exc})"
    return None


RT_SLEEP_MARGIN = 2.0
"""A spinning clock sleeps this many times the share of each tick that Linux keeps from
real-time tasks (:func:`realtime_idle_share`)."""


def realtime_idle_share() -> float:
    """The share of every period Linux keeps from real-time tasks (1 − runtime / period of
    ``/proc/sys/kernel/sched_rt_*``; 0 where there is no limit, 5 % where it cannot be read):
    a real-time task that runs longer is stopped for the rest of the period (1 s by
    default), a stall of tens of ticks."""
    try:
        runtime = int(Path("/proc/sys/kernel/sched_rt_runtime_us").read_text())
        period = int(Path("/proc/sys/kernel/sched_rt_period_us").read_text())
    except (OSError, ValueError):
        return 0.05
    if runtime < 0 or period <= 0:
        return 0.0
    return max(0.0, 1.0 - runtime / period)


class TickClock:
    """Fixed-period tick scheduler on ``time.monotonic`` with lateness statistics.

    ``tick_s`` is the period (s). Call :meth:`start` once, then per tick
    :meth:`wait` (sleeps until the tick is due and returns its index) and :meth:`done`
    (after the tick's work). ``lateness_s`` keeps the last ``history`` latenesses (s).
    ``spin_s`` (s): the last part of each wait is spent polling the clock instead of
    sleeping, so a late wake-up from sleep (tens of µs typically, milliseconds now and then
    on a virtual machine) costs no lateness; it costs that much CPU per tick. A spinning clock
    still sleeps :attr:`min_sleep_s` of every wait (less spin when the tick's work leaves
    less), so a real-time board never runs into Linux's real-time throttling.
    """

    def __init__(self, tick_s: float, history: int = 600_000, spin_s: float = 0.0) -> None:
        if not tick_s > 0:
            raise ValueError(f"tick_s must be > 0 s, got {tick_s!r}")
        if not 0 <= spin_s < tick_s:
            raise ValueError(f"spin_s must lie in [0, tick_s), got {spin_s!r}")
        self.tick_s = float(tick_s)
        self.spin_s = float(spin_s)
        self.min_sleep_s = (RT_SLEEP_MARGIN * realtime_idle_share() * self.tick_s
                            if spin_s > 0 else 0.0)
        """Sleep (s) every wait keeps before it spins (0 without spin)."""
        self.t0: float | None = None
        self.index = 0
        """Index of the next tick to run."""
        self.deadline_misses = 0
        self._late = LatenessLog(history)

    def start(self, t0: float | None = None) -> None:
        """Start the clock: tick 0 is due ``tick_s`` after ``t0`` (default now)."""
        self.t0 = time.monotonic() if t0 is None else t0
        self.index = 0

    def due(self, k: int) -> float:
        """Monotonic time (s) at which tick ``k``'s work is due."""
        assert self.t0 is not None, "start() the clock first"
        return self.t0 + (k + 1) * self.tick_s

    def wait(self, stop_check_s: float = 0.05) -> int:
        """Sleep until the next tick is due; return its index and record its lateness."""
        due = self.due(self.index)
        spin_s = min(self.spin_s, due - time.monotonic() - self.min_sleep_s)
        while True:
            now = time.monotonic()
            left = due - now
            if left <= 0:
                break
            if left > spin_s:
                time.sleep(min(left - spin_s, stop_check_s))
        self._late.record(now - due)
        return self.index

    def done(self) -> None:
        """Mark the current tick's work finished; count a miss if it ended too late."""
        if time.monotonic() > self.due(self.index) + self.tick_s:
            self.deadline_misses += 1
        self.index += 1

    def slack_s(self) -> float:
        """How long (s) until the next tick is due (negative when it is already late)."""
        return self.due(self.index) - time.monotonic()

    def behind_s(self) -> float:
        """How far (s) the next tick's due time lies in the past (0 if on time)."""
        return max(0.0, time.monotonic() - self.due(self.index))

    @property
    def ticks(self) -> int:
        """Ticks measured so far."""
        return self._late.count

    @property
    def max_lateness_s(self) -> float:
        """The largest lateness (s) of any tick so far."""
        return self._late.max_s

    def lateness_s(self, last: int | None = None) -> np.ndarray:
        """The recorded latenesses (s), oldest first: all kept (at most ``history``), or
        only the ``last`` ones."""
        return self._late.lateness_s(last)

    def lateness_percentiles_ms(self, qs: tuple[float, ...] = (50, 99),
                                last: int | None = None) -> dict[str, float]:
        """Lateness percentiles (over all kept ticks, or the ``last`` ones) and the maximum
        over the whole run, in ms (keys ``p50``, ``p99``, ``max``).

        Over all 60 000 ticks of a minute this takes about 8 ms: a live display inside the
        tick loop must use ``last`` (1000 ticks: tens of µs)."""
        return self._late.percentiles_ms(qs, last)
