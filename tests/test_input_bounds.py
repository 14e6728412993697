"""Inputs bounded where they enter: a schedule from a pipe nobody writes to is refused in
bounded time, overlapping presses cannot add up past the force cap (a schedule file or a
host's SET_STIMULUS), an output's temporary file never outlives a stop signal, and an
uppercase .NWB output is NWB."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from skinhil.errors import ConfigError
from skinhil.model import schedule_file
from skinhil.model.stimuli import MAX_FORCE_N
from skinhil.model.timeline import Timeline
from skinhil.output_files import atomic_path


def test_a_schedule_from_a_pipe_nobody_writes_is_refused_in_bounded_time(
        tmp_path, monkeypatch) -> None:
    fifo = tmp_path / "schedule.toml"
    os.mkfifo(fifo)
    monkeypatch.setattr(schedule_file, "READ_TIMEOUT_S", 0.3)
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match="no end of data"):
        schedule_file.load_schedule(fifo)
    assert time.monotonic() - t0 < 5.0
    # a pipe that is written is read whole
    r, w = os.pipe()
    os.write(w, b'[[event]]\nstart_s = 0\nstimulus = "A"\n')
    os.close(w)
    try:
        assert len(schedule_file.load_schedule(f"/proc/self/fd/{r}").entries) == 1
    finally:
        os.close(r)


def test_host_presses_stop_at_the_force_cap() -> None:
    timeline = Timeline(1e-4, None, 0, 0.25, Timeline.SCHEDULE_NONE)
    peak = abs(timeline.catalog[10].forces[15][2]) or max(map(abs, timeline.catalog[10].forces[15]))
    accepted = 0
    with pytest.raises(ConfigError, match=f"at most {MAX_FORCE_N:g} N"):
        for _ in range(10_000):
            timeline.start_stimulus(10, 0.0)
            accepted += 1
    assert accepted == int(MAX_FORCE_N / peak + 1e-9)
    assert timeline.start_stimulus(10, 10.0)  # once the presses ended, a new one is taken


def test_a_stop_signal_while_the_temporary_file_is_made_leaves_nothing(
        tmp_path, monkeypatch) -> None:
    made = []
    real = os.open

    def open_then_signal(name, *args, **kwargs):  # the signal lands right after creation
        fd = real(name, *args, **kwargs)
        if ".partial" in str(name):
            made.append(Path(name))
            os.kill(os.getpid(), signal.SIGINT)
        return fd

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    monkeypatch.setattr(os, "open", open_then_signal)
    try:
        with pytest.raises(KeyboardInterrupt):
            with atomic_path(tmp_path / "out.npz") as tmp:
                tmp.write_bytes(b"x")
    finally:
        monkeypatch.undo()
        signal.signal(signal.SIGINT, previous)
    assert made and not made[0].exists()
    assert list(tmp_path.iterdir()) == []


def test_an_uppercase_nwb_output_is_nwb(tmp_path) -> None:
    """``simulate --out x.NWB`` writes NWB (HDF5), not an npz under that name."""
    pytest.importorskip("pynwb")
    from skinhil.cli import main

    out = tmp_path / "run.NWB"
    assert main(["simulate", "--duration", "0.01", "--no-progress", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89HDF\r\n\x1a\n"


def test_the_decision_log_is_bounded(monkeypatch) -> None:
    """A decoder under test that floods the board with DECISIONs cannot grow the per-decision
    log (memory, the --score file) without bound: every decision is counted, the first ones
    are logged and the rest said omitted."""
    from skinhil.scoring import scoreboard

    monkeypatch.setattr(scoreboard, "MAX_LOGGED_DECISIONS", 50)
    board = scoreboard.DecisionScoreboard(0.5)
    board.onset(1, 0)
    for k in range(500):
        board.decision(1, 1_000 * k, None, True, k)
    summary = board.summary(with_log=True)
    assert summary["decisions"] == 500
    assert len(summary["log"]) == 50 and summary["log_omitted"] == 450
