"""Child processes that die with their parent, whatever signal ends it.

Every process skinhil starts (``bench``'s board and reference receiver, ``demo``'s board, a
board warming the kernel cache) is started by :func:`start`: on Linux the child asks the
kernel for a parent-death signal (``prctl(PR_SET_PDEATHSIG, SIGTERM)``) before it runs its
program, so a parent ended by SIGKILL, or by any signal it does not handle, still takes its
children with it (:mod:`skinhil.workers`' forked workers ask for the same with
:func:`die_with_parent`); a parent that stops cleanly ends them itself first. SIGTERM lets a child
that is a skinhil command stop as it does on a terminal's Ctrl-C (its temporary files
removed, its own children ended). The request is kept across ``exec``; it is made from the
thread that starts the child, which is the thread that waits for it here.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Sequence
from typing import Any

PR_SET_PDEATHSIG = 1
"""``prctl`` option (linux/prctl.h): the signal a process gets when its parent ends."""
DEATH_SIGNAL = signal.SIGTERM
"""What a child gets when its parent ends."""


def _libc_prctl() -> Callable[..., int] | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
    except OSError:
        return None
    prctl: Callable[..., int] = libc.prctl
    return prctl


_PRCTL = _libc_prctl()


def die_with_parent(parent: int) -> None:
    """Ask for :data:`DEATH_SIGNAL` when this process's parent ends (a forked worker calls
    it first thing); if the parent (``parent``: its pid) has already ended, exit at once."""
    if _PRCTL is not None:
        _PRCTL(PR_SET_PDEATHSIG, int(DEATH_SIGNAL), 0, 0, 0)
    if os.getppid() != parent:  # the parent ended before the request was made
        os._exit(1)


def _die_with(parent: int) -> Callable[[], None]:
    def preexec() -> None:  # runs in the child, between fork and exec
        die_with_parent(parent)
    return preexec


def start(cmd: Sequence[str], **kwargs: Any) -> subprocess.Popen[Any]:
    """``subprocess.Popen(cmd, **kwargs)`` for a child that ends when this process ends
    (see the module docstring)."""
    return subprocess.Popen(list(cmd), preexec_fn=_die_with(os.getpid()), **kwargs)
