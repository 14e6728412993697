"""Machine and command description printed at the top of every benchmark."""

from __future__ import annotations

import os
import platform
import sys


def cpu_model() -> str:
    """The CPU's model name as lscpu and /proc/cpuinfo give it."""
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def describe() -> str:
    """One block of text: CPU, cores, OS, Python and key package versions, the command."""
    cpu = cpu_model()
    import numba
    import numpy
    import scipy

    return (f"machine: {cpu}, {os.cpu_count()} cores, {platform.platform()}\n"
            f"python {platform.python_version()}, numpy {numpy.__version__}, "
            f"scipy {scipy.__version__}, numba {numba.__version__}\n"
            f"command: {' '.join([os.path.basename(sys.executable)] + sys.argv)}")


def load_average() -> str:
    """The machine's 1, 5 and 15 minute load averages (all cores; this run included)."""
    la = os.getloadavg()
    return f"load average {la[0]:.2f} {la[1]:.2f} {la[2]:.2f} on {os.cpu_count()} cores"


def pin_one_core() -> None:
    """Run on one core (the first allowed) with single-threaded BLAS, where the OS allows."""
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
