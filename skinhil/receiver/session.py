"""Run a board subprocess (``skinhil serve``) against a :class:`Receiver` until it ends.

Used by ``skinhil demo``, the end-to-end tests and the latency benchmark, so each does not
re-implement the loop: poll the link, stop once the board has exited and the link has been
quiet for ``idle_s``, then flush the last windows.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from typing import Any, Protocol

from skinhil import child_processes
from skinhil.errors import TransportError


class StreamReader(Protocol):
    """What the loop reads of a receiver (:class:`skinhil.receiver.Receiver`,
    :class:`skinhil.receiver.grip_loop.GripLoop`)."""

    transport: Any
    run_end: Any

    def feed(self, payload: Any, host_s: float | None = None) -> list[Any]: ...

    def flush(self) -> list[Any]: ...


def serve_command(link_args: Sequence[str], duration_s: float, snr_db: float, seed: int,
                  rest_s: float = 0.25) -> list[str]:
    """The ``skinhil serve`` command line for a board on ``link_args`` (e.g. --port P)."""
    return [sys.executable, "-m", "skinhil", "serve", *link_args, "--duration", str(duration_s),
            "--snr-db", str(snr_db), "--seed", str(seed), "--rest", str(rest_s), "--quiet"]


def run_against_board(receiver: StreamReader, command: Sequence[str], idle_s: float = 0.3,
                      timeout_s: float = 600.0, stop: threading.Event | None = None
                      ) -> tuple[int, str, str]:
    """Start ``command`` and feed ``receiver`` until the board's RUN_END record (or, if it
    never comes, ``idle_s`` of silence after the board exited); (status, stdout, stderr).

    The board runs in a session of its own, so a Ctrl-C at the terminal reaches only this
    process: once ``stop`` is set, the board gets one SIGINT and stops cleanly (its FIFO
    drained, its score and RUN_END written), and it is fed until then."""
    board = child_processes.start(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, start_new_session=True)
    end = time.monotonic() + timeout_s
    forwarded = False
    try:
        idle_since = None
        while time.monotonic() < end:
            if stop is not None and stop.is_set() and not forwarded:
                forwarded = True
                board.send_signal(signal.SIGINT)
            try:
                payload = receiver.transport.recv(0.02)
            except TransportError:
                payload = receiver.transport.empty()
            receiver.feed(payload, time.monotonic())
            if receiver.run_end is not None:  # the board's last record: nothing follows
                break
            if board.poll() is None:
                continue
            if payload:
                idle_since = None
            elif idle_since is None:
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since > idle_s:
                break
        receiver.flush()
        out, err = board.communicate(timeout=10)
    finally:
        if board.poll() is None:
            board.terminate()
            board.wait(timeout=5)
    return int(board.returncode), out, err
