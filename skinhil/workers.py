"""Local worker processes: one way to map a function over tasks on several cores.

:func:`process_map` runs ``fn`` over the tasks in a :class:`~concurrent.futures.
ProcessPoolExecutor` (the standard library's: no helper process of its own, such as a
resource tracker, that could outlive a stop) and returns the results in task order, so a
result never depends on how many workers ran it. Each worker runs one BLAS thread (concurrent
tasks in one process cannot change each other's thread count, and with it the rounding),
ignores Ctrl-C (sent to the terminal's whole process group: the parent ends its workers
itself) and ends quietly on SIGTERM (a forked worker would otherwise keep its parent's
handler). On a stop or a failure the pool is shut down without waiting for the tasks still
running.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TypeVar

from threadpoolctl import threadpool_limits

from skinhil.child_processes import die_with_parent
from skinhil.errors import ConfigError

T = TypeVar("T")
R = TypeVar("R")


def one_blas_thread() -> None:
    """Worker set-up: one BLAS thread for the whole process (see the module docstring)."""
    threadpool_limits(1)


def _local_worker(parent: int) -> None:
    die_with_parent(parent)  # a parent ended by SIGKILL takes its workers with it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    one_blas_thread()


def worker_count(workers: int | None) -> int:
    """``workers`` checked (>= 1), or every core when None."""
    n = (os.cpu_count() or 1) if workers is None else int(workers)
    if n < 1:
        raise ConfigError(f"workers must be >= 1, got {workers}")
    return n


def process_map(fn: Callable[[T], R], tasks: Sequence[T], workers: int | None = None,
                on_result: Callable[[R], None] | None = None) -> list[R]:
    """``[fn(t) for t in tasks]`` on ``workers`` processes (None: every core; 1, or a single
    task, runs here); ``on_result`` is called with each result as it arrives, in order
    (a progress bar's update). ``fn`` and the tasks must pickle."""
    n = min(worker_count(workers), len(tasks))
    out: list[R] = []
    if n <= 1:
        for task in tasks:
            out.append(fn(task))
            if on_result is not None:
                on_result(out[-1])
        return out
    pool = ProcessPoolExecutor(max_workers=n, initializer=_local_worker,
                               initargs=(os.getpid(),))
    try:
        chunk = max(1, len(tasks) // (8 * n))
        for res in pool.map(fn, tasks, chunksize=chunk):
            out.append(res)
            if on_result is not None:
                on_result(res)
    except BaseException:  # stopped or failed: no waiting for the tasks still running
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()
    return out

