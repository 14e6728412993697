"""How the command line stops: SIGINT (Ctrl-C), SIGTERM and SIGHUP (the terminal closed),
from the first instruction on.

:func:`install` is the first thing :func:`skinhil.cli.main` does (before any heavy import):
from then on each of them raises :class:`Stopped` (a ``KeyboardInterrupt``) in the main
thread, so every ``finally`` runs (temporary output files are removed, links closed, worker
processes ended) and :func:`skinhil.cli.main` exits with status 130 (SIGINT), 143
(SIGTERM) or 129 (SIGHUP) and one line, never a traceback. A signal that lands where
Python would lose the exception (a callback from native code, an import lock's weakref
callback, a finalizer) is delivered again once back in Python's own code; a write that
must not be torn (numpy's zip writer) runs inside :func:`held`, which delivers it after.
A command with a summary catches :class:`Stopped`, prints what it has and re-raises.

A command that stops cleanly on request (``serve``, ``listen``: they drain the link and print
their totals) runs its loop inside :func:`stop_event`: the first signal only sets the event;
a second one raises :class:`Stopped` at once, after saying what was left undrained.
"""

from __future__ import annotations

import contextlib
import logging  # noqa: F401 - imported before the fork hooks below, so its own run inside them
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType

STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
"""The signals that stop a command."""

_received: list[int] = []
_deferred: list[bool] = [False]
_forking: list[bool] = [False]


def _fork_begins() -> None:
    _forking[0] = True


def _fork_ends() -> None:
    _forking[0] = False


# A fork (a worker pool starting a process) runs Python callbacks registered with
# os.register_at_fork (logging's lock handling) from C: an exception raised there is printed
# as "Exception ignored" and lost. These hooks, registered after logging's, run first before
# the fork and last after it, so a stop signal in between is delivered again once it is over.
os.register_at_fork(before=_fork_begins, after_in_parent=_fork_ends,
                    after_in_child=_fork_ends)
_FORK_HOOKS = (_fork_begins.__code__, _fork_ends.__code__)


class Stopped(KeyboardInterrupt):
    """Raised in the main thread by a stop signal (:data:`STOP_SIGNALS`); ``signum`` says
    which."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_status(self) -> int:
        """The shell's convention: 128 + the signal number (130 SIGINT, 143 SIGTERM, 129
        SIGHUP)."""
        return 128 + self.signum


NATIVE_CALLBACKS: tuple[str, ...] = (os.path.join("", "llvmlite", ""),
                                     os.path.join("", "numba", "core", "serialize.py"))
"""Where the Python functions live that native code calls back: llvmlite (numba's compiler),
whose exceptions are printed as "Exception ignored" and lost, and numba's unpickler, which a
compiled function calls as it returns an array (its dtype), whose exception the compiled
code does not check (a Ctrl-C there ended ``simulate`` with "SystemError: CPUDispatcher(...)
returned a result with an exception set")."""
IMPORT_CALLBACKS: tuple[str, ...] = ("<frozen importlib._bootstrap>",)
"""Where the import system's weakref callbacks live (a module lock's ``cb``): an exception
raised in one is printed as "Exception ignored" and lost, and the import goes on."""
RESEND_S = 0.02
"""How soon (s) a signal that arrived inside such a callback is delivered again."""


def _in_native_callback(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs in code whose exceptions are lost: a callback from native code
    (:data:`NATIVE_CALLBACKS`), a fork's callbacks, or a finalizer (``__del__``) anywhere up
    its stack."""
    if _forking[0] or (frame is not None and frame.f_code in _FORK_HOOKS):
        return True
    while frame is not None:
        code = frame.f_code
        if code.co_name == "__del__" or any(place in code.co_filename
                                            for place in NATIVE_CALLBACKS):
            return True
        if code.co_name == "cb" and code.co_filename in IMPORT_CALLBACKS:
            return True
        frame = frame.f_back
    return False


def _raise(signum: int, frame: FrameType | None) -> None:
    _received.append(signum)
    if _deferred[0]:
        return
    if _in_native_callback(frame):  # raise it again once back in Python's own code
        threading.Timer(RESEND_S, os.kill, (os.getpid(), signum)).start()
        return
    raise Stopped(signum)


Handlers = dict[signal.Signals, object]
"""Signal handlers as :func:`signal.signal` returns them."""


def install() -> Handlers:
    """Make the stop signals (:data:`STOP_SIGNALS`) raise :class:`Stopped` in the main thread, once
    :func:`resume` is called: until then (the start-up's imports) they are only recorded,
    since an exception inside an extension module's import (numpy's) turns into an
    ImportError with pages of advice instead of a clean stop. Returns the handlers it
    replaced, for :func:`restore`."""
    _received.clear()
    _deferred[0] = True
    return {s: signal.signal(s, _raise) for s in STOP_SIGNALS}


def restore(handlers: Handlers) -> None:
    """Put back the handlers :func:`install` replaced (a caller in the same process, such
    as a test calling :func:`skinhil.cli.main`, gets its own back)."""
    for s, h in handlers.items():
        signal.signal(s, h)  # type: ignore[arg-type]


def resume() -> None:
    """End the start-up: a stop signal received meanwhile raises :class:`Stopped` now, later
    ones at once."""
    _deferred[0] = False
    if _received:
        raise Stopped(_received[0])


def finish() -> None:
    """The command is done and its exit status decided: a stop signal from now on (while the
    interpreter shuts down: joining threads, flushing) is only recorded, never a traceback."""
    _deferred[0] = True


@contextlib.contextmanager
def held() -> Iterator[None]:
    """While the body runs (a write a stop must not tear, such as numpy's zip writer, whose
    own clean-up on an exception raises again), a stop signal is only recorded; it raises
    :class:`Stopped` as the body ends, whether the body ended cleanly or not (its
    ``finally`` has run: a temporary file is removed)."""
    before = _deferred[0]
    _deferred[0] = True
    try:
        yield
    finally:
        _deferred[0] = before
        if not before and _received:
            raise Stopped(_received[0])


def received() -> int | None:
    """The first stop signal received so far (None: none)."""
    return _received[0] if _received else None


def exit_status(status: int) -> int:
    """``status``, or 128 + the signal number when a stop signal was received (a command
    that stopped cleanly on Ctrl-C still exits 130)."""
    first = received()
    return status if first is None else 128 + first


@contextlib.contextmanager
def stop_event(on_first: Callable[[], str | None] | None = None,
               on_second: Callable[[], str | None] | None = None) -> Iterator[threading.Event]:
    """While the body runs, the first stop signal sets the yielded event (the body stops
    cleanly: drains, prints totals) and prints ``on_first()``'s line, if any (say what the
    clean stop will wait for); a second one prints ``on_second()``'s line (what is left
    undrained) and raises :class:`Stopped` at once. The previous handlers come back after."""
    stop = threading.Event()

    def handler(signum: int, frame: FrameType | None) -> None:
        _received.append(signum)
        if not stop.is_set():
            stop.set()
            line = on_first() if on_first is not None else None
        elif _in_native_callback(frame):
            threading.Timer(RESEND_S, os.kill, (os.getpid(), signum)).start()
            return
        else:
            line = on_second() if on_second is not None else None
            if line:
                print(f"skinhil: {line}", file=sys.stderr, flush=True)
            raise Stopped(signum)
        if line:
            print(f"skinhil: {line}", file=sys.stderr, flush=True)

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    try:
        yield stop
    finally:
        for s, h in old.items():
            signal.signal(s, h)


CHILD_GRACE_S = 1.0
"""How long (s) :func:`end_children` waits for the killed processes to be gone."""


def _descendants(pid: int) -> list[int]:
    """Every live descendant of process ``pid`` (Linux ``/proc``; none elsewhere)."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:  # the process ended meanwhile
            continue
        fields = text[text.rfind(")") + 2:].split()
        parents.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = [], [pid]
    while todo:
        kids = parents.get(todo.pop(), [])
        out += kids
        todo += kids
    return out


def end_children(grace_s: float = CHILD_GRACE_S) -> None:
    """End every process this one started (worker pools, a board in a subprocess) with
    SIGKILL, at once: a forked worker still has this process's handlers and would print a
    stop of its own; none holds anything worth saving (outputs are written by this process,
    atomically). Waits at most ``grace_s`` (s) for them to be gone."""
    kids = _descendants(os.getpid())
    for pid in kids:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    end = time.monotonic() + grace_s
    while kids and time.monotonic() < end:
        kids = [pid for pid in kids if _alive(pid)]
        time.sleep(0.02)


def _alive(pid: int) -> bool:
    """Whether ``pid`` still runs (an exited child not yet reaped, a zombie, does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return state[state.rfind(")") + 2:][:1] not in ("Z", "X")
