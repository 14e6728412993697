"""What the demo prepares on first use: where it caches what it fits (its decoder, the grip
readout), and the board's kernels warmed meanwhile in another process."""

from __future__ import annotations

import contextlib
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

from skinhil import child_processes
from skinhil.model.timeline import DEFAULT_REST_S
from skinhil.receiver.session import serve_command
from skinhil.transports import PtyMasterTransport


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/skinhil`` or ``~/.cache/skinhil``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "skinhil"


@contextlib.contextmanager
def board_warming(baud: int, snr_db: float, seed: int) -> Iterator[None]:
    """While the body runs, a one-tick board (the demo's command line) on a throwaway pty
    compiles or loads the board's kernels in another process, on the other core: from a
    fresh clone that is ~15 s the demo's board then does not spend before its first tick."""
    link, slave_fd = PtyMasterTransport.open_pair(baud)
    board = child_processes.start(
        serve_command(["--port", link.slave_path, "--baud", str(baud)], 0.001, snr_db, seed,
                      DEFAULT_REST_S), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    try:
        yield
        board.wait(timeout=600)
    finally:
        if board.poll() is None:
            board.kill()
            board.wait()
        link.shutdown()
        os.close(slave_fd)
