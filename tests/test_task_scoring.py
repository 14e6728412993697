"""A scripted decoder under test over a pty answers every task (SPEC.md §3.5.3-§3.5.5): its
right, wrong, duplicate, late and missing answers and its false alarms each land in their own
counter of the board's score; on the blind link no byte of truth reaches it."""

from __future__ import annotations

import os
import select
import threading
import time
from pathlib import Path

import pytest
from harness.schemas import check_lines

import protocols
from firmware_sim.board import Board, BoardConfig
from protocols import Answer, Task
from skinhil.cli.parser import build_parser
from skinhil.cli.serve import _config, write_truth
from skinhil.model.timeline import Timeline
from skinhil.transports import SerialTransport
from skinhil.world.scenario_file import parse_scenario

WINDOW_S = 0.3
CONTACT = """
[[contact]]
indenter = "ball"
start_s = {start}
motion = "slide"
x_mm = -1.0
to_x_mm = 1.0
speed_mm_per_s = 20.0
load_n = 0.3
ramp_s = 0.03
dwell_s = 0.1
mu_static = 0.4
mu_kinetic = 0.3
vibration_mm = 0.02
vibration_hz = {hz}
vibration_axis = "y"
"""
SCENARIO = ('[[indenter]]\nname = "ball"\nshape = "sphere"\nradius_mm = 5.0\n'
            + "".join(CONTACT.format(start=s, hz=hz)
                      for s, hz in ((0.05, 100.0), (0.85, 250.0), (1.65, 100.0)))
            + '[[event]]\nstart_s = 2.2\nstimulus = "A"\n')
"""Three sliding, vibrating touches 0.8 s apart (each a touch, then a slip ~0.14 s later),
then the paper's stimulus A (a MARKER falls due: withheld on the blind link)."""
DURATION_S = 2.6
TOUCH_TASKS = (Task.LOCALISATION, Task.FORCE, Task.VIBRATION)


class RawPeer:
    """The decoder's end of the pty: every byte it receives, kept, and ANSWERs sent."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.chunks: list[bytes] = []
        self.encoder = protocols.SerialEncoder()
        self.token = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.fd], [], [], 0.02)
            if ready:
                try:
                    self.chunks.append(os.read(self.fd, 65536))
                except OSError:
                    time.sleep(0.01)

    def answer(self, task: Task, *values: float) -> int:
        self.token += 1
        os.write(self.fd, self.encoder.command(Answer(self.token, task, tuple(values))))
        return self.token

    def close(self) -> None:
        self._stop.set()
        self._thread.join(1.0)


def _script(board: Board, peer: RawPeer, sent: dict[str, list[tuple[Task, int]]]) -> None:
    """The decoder under test, timed by the board's truth (the test's privilege)."""
    tasks = board.tasks
    assert tasks is not None

    def trial(task: Task, k: int):  # type: ignore[no-untyped-def]
        score = tasks.tasks[task]
        end = time.monotonic() + 120  # a cold kernel cache compiles first
        while len(score.trials) <= k and time.monotonic() < end:
            time.sleep(0.002)
        return score.trials[k]

    def until_us(t_us: int) -> None:
        end = time.monotonic() + 120
        while board.board_time_us() < t_us and time.monotonic() < end:
            time.sleep(0.002)

    def send(kind: str, task: Task, *values: float) -> None:
        sent.setdefault(kind, []).append((task, peer.answer(task, *values)))

    for k in range(3):
        for task in TOUCH_TASKS:
            t = trial(task, k)
            until_us(t.t0_us + 30_000)  # the touch has settled
            truth = {Task.LOCALISATION: (t.x_mm, t.y_mm), Task.FORCE: (t.normal_n,),
                     Task.VIBRATION: (t.frequency_hz,)}[task]
            if k == 0:
                send("right", task, *truth)
                send("duplicates", task, *truth)
            elif k == 1:
                wrong = {Task.LOCALISATION: (t.x_mm + 3.0, t.y_mm), Task.FORCE: (
                    t.normal_n + 0.5,), Task.VIBRATION: (100.0,)}[task]  # this one is 250 Hz
                send("wrong", task, *wrong)
        s = trial(Task.SLIP, k)
        until_us(s.t0_us + 10_000)
        if k < 2:
            send("right", Task.SLIP)
        if k == 0:
            send("duplicates", Task.SLIP)
        until_us(s.t0_us + int(WINDOW_S * 1e6) + 60_000)  # every window of trial k passed
        for task in (*TOUCH_TASKS, Task.SLIP):
            if k == 0:  # after a decided trial's window: nothing to answer
                send("false_alarms", task, *{Task.LOCALISATION: (0.0, 0.0), Task.FORCE: (
                    0.3,), Task.VIBRATION: (100.0,), Task.SLIP: ()}[task])
            elif k == 2:  # the trial went unanswered (a miss): its answer comes late
                t = trial(task, 2)
                send("late", task, *{Task.LOCALISATION: (t.x_mm, t.y_mm), Task.FORCE: (
                    t.normal_n,), Task.VIBRATION: (t.frequency_hz,), Task.SLIP: ()}[task])
    until_us(int(2.2e6) + 50_000)
    send("classification", Task.CLASSIFICATION, 13)  # stimulus A is id 10: a wrong DECISION


def test_scripted_decoder_lands_in_every_counter_on_a_blind_link(pty_pair, tmp_path: Path
                                                                  ) -> None:
    scenario = parse_scenario(SCENARIO, "test scenario")
    config = BoardConfig(snr_db=10.0, seed=1, schedule_mode=Timeline.SCHEDULE_FILE,
                         response_window_s=WINDOW_S, markers=False)
    peer = RawPeer(pty_pair.master)
    sent: dict[str, list[tuple[Task, int]]] = {}
    try:
        board = Board(config, lambda: SerialTransport(pty_pair.path, baud=921600),
                      scenario.schedule, scene=scenario.scene)
        script = threading.Thread(target=_script, args=(board, peer, sent), daemon=True)
        script.start()
        summary = board.run(DURATION_S)
        script.join(5)
        time.sleep(0.2)
    finally:
        peer.close()
    tasks = summary.tasks
    for task in (*TOUCH_TASKS, Task.SLIP):
        got = tasks[task.name.lower()]
        assert got["trials"] == 3, (task, got)
        for kind in ("right", "wrong", "duplicates", "late", "false_alarms"):
            want = sum(1 for t, _ in sent.get(kind, []) if t == task)
            assert got[kind] == want, (task, kind, got)
        assert got["misses"] == 1 and got["while_stopped"] == 0, got  # trial 2
        assert got["answers"] == sum(got[k] for k in ("right", "wrong", "duplicates", "late",
                                                       "false_alarms", "while_stopped"))
    assert tasks["slip"]["right"] == 2 and tasks["slip"]["false_alarms_per_min"] > 0
    assert tasks["localisation"]["median_error_mm"] is not None
    assert tasks["vibration"]["classes_hz"] == [100.0, 250.0]
    # an ANSWER of task CLASSIFICATION is scored as a DECISION
    assert summary.scoreboard["onsets"] == 1 and summary.scoreboard["wrong"] == 1
    # the blind link: every byte the decoder got belongs to a good packet, none of them truth
    data = b"".join(peer.chunks)
    dec = protocols.SerialDecoder()
    records = dec.feed(data).records
    c = dec.counters
    assert c.crc_errors == c.malformed == c.bytes_discarded == c.frames_lost == 0
    packets = [p for p in data.split(b"\x00") if p]
    assert len(packets) == c.frames_ok  # no byte outside a decoded packet
    kinds = {type(r).__name__ for r in records}
    assert kinds <= {"Session", "StimulusEntry", "SuiteEntry", "Status", "Ack", "RunEnd"}, kinds
    assert not any(isinstance(r, protocols.Marker) for r in records)
    assert all(r.markers_sent == 0 for r in records if isinstance(r, protocols.Status))
    assert [m.phase for m in board.truth_markers] == ["onset", "end"]  # kept for the operator
    acks = [r for r in records if isinstance(r, protocols.Ack)]
    assert len(acks) == sum(len(v) for v in sent.values()) and all(a.ok for a in acks)
    # the operator's truth file: the markers and every trial, with its values
    write_truth(tmp_path / "truth.jsonl", board)
    rows = check_lines("truth-line", tmp_path / "truth.jsonl")  # against its schema
    assert [r["phase"] for r in rows if r["type"] == "marker"] == ["onset", "end"]
    trials = [r for r in rows if r["type"] == "trial"]
    assert sorted({r["task"] for r in trials}) == ["force", "localisation", "slip", "vibration"]
    assert len(trials) == 12
    force = [r["normal_n"] for r in trials if r["task"] == "force"]
    assert all(abs(f - 0.3) < 0.05 for f in force), force  # the load, settled at 50 ms


def test_serve_score_is_blind_unless_markers_are_asked_for() -> None:
    parser = build_parser()
    serve = ["serve", "--port", "/dev/null"]
    assert _config(parser.parse_args(serve)).markers  # no scoring: today's stream
    assert not _config(parser.parse_args([*serve, "--score", "s.json"])).markers
    assert _config(parser.parse_args([*serve, "--score", "s.json", "--markers"])).markers


def test_answer_range_is_what_the_wire_carries() -> None:
    enc, dec = protocols.SerialEncoder(), protocols.SerialDecoder()
    for task, n in ((Task.LOCALISATION, 2), (Task.FORCE, 1), (Task.VIBRATION, 1)):
        lo, hi = protocols.answer_range(task)
        for v in (lo, hi):
            got = dec.feed(enc.command(Answer(1, task, (v,) * n))).records
            assert [a.values for a in got] == [pytest.approx((v,) * n)]
        with pytest.raises(protocols.errors.ProtocolError):
            enc.command(Answer(1, task, (hi + 2 * protocols.ANSWER_SCALE[task],) * n))
