"""A host program on one end of a socat pty pair and ``skinhil serve`` on the other, as a
user runs a decoder beside the board (a linked pair of ptys stands for the cable)."""

from __future__ import annotations

import contextlib
import select
import shutil
import signal
import subprocess
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

from harness.serve import RUN_DIR, run_serve, serve_env


@contextlib.contextmanager
def linked_ptys(folder: Path) -> Iterator[tuple[Path, Path]]:
    """(board end, host end): the paths of a socat pty pair in ``folder``; skips the test
    where socat is missing."""
    if shutil.which("socat") is None:
        pytest.skip("socat is not installed (apt-get install socat)")
    board_end, host_end = folder / "ttyBOARD", folder / "ttyHOST"
    socat = subprocess.Popen(["socat", f"pty,raw,echo=0,link={board_end}",
                              f"pty,raw,echo=0,link={host_end}"])
    try:
        end = time.monotonic() + 10
        while not (board_end.exists() and host_end.exists()):
            assert time.monotonic() < end, "socat made no pty pair"
            time.sleep(0.05)
        yield board_end, host_end
    finally:
        socat.kill()
        socat.wait()


Finished = subprocess.CompletedProcess[str]


def host_beside_serve(folder: Path, host_argv: Sequence[str], serve_args: Sequence[str],
                      timeout_s: float = 120.0, own_end_s: float = 0.0,
                      host_ready: bool = False) -> tuple[Finished, Finished]:
    """Run ``host_argv`` on the host end (``{HOST}`` in it is replaced by the path) and
    ``skinhil serve --port <board end> serve_args`` to completion, then give the host up to
    ``own_end_s`` to end by itself (``skinhil listen`` does at the board's RUN_END record)
    before stopping it with SIGINT; (serve's result, the host's result), output as text.
    ``host_ready``: start the board only once the host printed its first line (``listen
    --json``'s ready line: its link is open), as a user starts the decoder first."""
    with linked_ptys(folder) as (board_end, host_end):
        argv = [str(host_end) if a == "{HOST}" else a for a in host_argv]
        host = subprocess.Popen(argv, cwd=RUN_DIR, env=serve_env(), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        first = ""
        try:
            if host_ready:
                assert host.stdout is not None
                ready, _, _ = select.select([host.stdout], [], [], timeout_s)
                assert ready, f"the host printed nothing within {timeout_s:g} s"
                first = host.stdout.readline()
            board = run_serve("--port", str(board_end), *serve_args, timeout_s=timeout_s)
            time.sleep(0.5)  # the host reads and answers what is left on the link
            try:
                host.wait(timeout=own_end_s)
            except subprocess.TimeoutExpired:
                host.send_signal(signal.SIGINT)
            try:
                out, err = host.communicate(timeout=30)
            except subprocess.TimeoutExpired:  # a scripted host blocked on a link gone quiet
                host.kill()
                out, err = host.communicate()
        finally:
            if host.poll() is None:
                host.kill()
                host.wait()
    return board, subprocess.CompletedProcess(argv, host.returncode, first + out, err)
