"""The SESSION's announcement of a suite case (SPEC.md §3.7): the SUITE and TASK records a
board sends after its stimulus table, the held-object flag, their checks on the serial
layout, and what the receiver gathers of them."""

from __future__ import annotations

import struct
from typing import Any

import pytest
from harness.golden import GoldenLink
from protocol_examples import framed

import protocols
from firmware_sim.board import Board, BoardConfig
from skinhil.errors import ConfigError, ProtocolError
from skinhil.model.timeline import Timeline
from skinhil.receiver.announcement import Announcement
from skinhil.suites import case_ref, suite_trials
from skinhil.suites.announcement import announcement
from skinhil.tasks.registry import by_name

TICKS = 30
"""Ticks a board plays off the clock: its start's records are all the test reads."""


def _records(ref: str, frames: bool, fd: bool = False) -> list[Any]:
    """The records a board playing the case ``ref`` (seed 1) sends in its first ticks, as
    the protocol decoder of its link returns them."""
    trials = suite_trials(ref, 1)
    config = BoardConfig(seed=1, schedule_mode=Timeline.SCHEDULE_FILE,
                         tasks=tuple(t.name for t in trials.tasks),
                         **announcement(*case_ref(ref))).check()
    link = GoldenLink(frames, can_fd=fd)
    board = Board(config, lambda: link, trials.scenario.schedule,
                  scene=trials.scenario.scene, grasp=trials.grasp)
    board.warm_up()
    board.queue_session(protocols.SessionReason.START)
    for k in range(TICKS):
        link.tick = k
        board.tick()
    dec = link.codec_pair(board_id=0)[1]
    res = dec.feed(link.units if frames else b"".join(link.units))
    assert dec.counters.malformed == 0
    return list(res.records)


@pytest.mark.parametrize(("frames", "fd"), [(False, False), (True, False), (True, True)])
def test_a_case_is_announced_after_the_stimulus_table(frames: bool, fd: bool) -> None:
    recs = _records("tactile-v1:vibration", frames, fd)
    session = recs[0]
    assert isinstance(session, protocols.Session) and not session.held_object
    n = session.n_stimuli
    assert all(isinstance(r, protocols.StimulusEntry) for r in recs[1:1 + n])
    suite, task = recs[1 + n:3 + n]
    assert suite == protocols.SuiteEntry("tactile", 1, "vibration", 1)
    (posed,) = suite_trials("tactile-v1:vibration", 1).tasks
    assert task == protocols.TaskEntry(protocols.Task.VIBRATION, None, "Hz", posed.classes)
    # every announced task is posed: its bit is in the SESSION's tasks
    assert session.tasks & (1 << int(task.task))
    got = Announcement()
    assert [got.take(r) for r in recs[:3 + n]][-1] is True
    assert got.as_dict() == {
        "suite": {"id": "tactile-v1", "name": "tactile", "version": 1, "case": "vibration"},
        "held_object": False, "blind": session.blind,
        "tasks": {"vibration": {"tolerance": None, "unit": "Hz",
                                "classes": list(posed.classes)}}}


def test_a_tolerance_is_announced_with_its_unit() -> None:
    recs = _records("tactile-v1:force", False)
    task = next(r for r in recs if isinstance(r, protocols.TaskEntry))
    (posed,) = suite_trials("tactile-v1:force", 1).tasks
    assert (task.task, task.tolerance, task.unit) == (
        by_name("force").wire_id, posed.tolerance, posed.unit)


def test_a_held_object_is_announced_in_the_session() -> None:
    recs = _records("tactile-v1:grasp", True)
    assert recs[0].held_object
    suite = next(r for r in recs if isinstance(r, protocols.SuiteEntry))
    assert suite == protocols.SuiteEntry("tactile", 1, "grasp", 0)
    assert not any(isinstance(r, protocols.TaskEntry) for r in recs)


def test_the_board_refuses_a_half_announced_suite() -> None:
    with pytest.raises(ConfigError, match="or none of them"):
        BoardConfig(suite_name="tactile", suite_version=1).check()
    with pytest.raises(ConfigError, match="or none of them"):
        BoardConfig(task_terms=(protocols.TaskEntry(2, 0.05, "N"),)).check()
    with pytest.raises(ConfigError, match="suite_name"):
        BoardConfig(suite_name="x" * 33, suite_version=1, suite_case="c").check()


def test_the_encoder_refuses_what_the_wire_cannot_carry() -> None:
    enc = protocols.SerialEncoder()
    for bad in (protocols.SuiteEntry("tactile", 1, ""), protocols.SuiteEntry("", 1, ""),
                protocols.SuiteEntry("é" * 17, 1, "c"),
                protocols.TaskEntry(2, -0.1, "N"), protocols.TaskEntry(2, float("inf"), "N"),
                protocols.TaskEntry(4, None, "Hz", (1.0,) * 25),
                protocols.TaskEntry(4, None, "Hz", (float("nan"),)),
                protocols.TaskEntry(16, None), protocols.TaskEntry(2, 0.1, "newtons!!")):
        with pytest.raises(ProtocolError):
            enc.session_record(bad)


def _suite_body(version: int, n_tasks: int, name: bytes, case: bytes) -> bytes:
    return bytes([7 << 5 | 3, 0]) + struct.pack("<HBBB", version, n_tasks, len(name),
                                                 len(case)) + name + case


def _task_body(task: int, tol_bits: int, unit: bytes, classes: list[int]) -> bytes:
    return (bytes([7 << 5 | 4, 0]) + struct.pack("<BBIB", task, len(classes), tol_bits,
                                                  len(unit))
            + unit + b"".join(struct.pack("<I", c) for c in classes))


@pytest.mark.parametrize(("body", "good"), [
    (_suite_body(1, 1, b"tactile", b"force"), True),
    (_suite_body(0, 0, b"", b""), True),
    (_suite_body(1, 0, b"", b""), False),          # a version without a suite
    (_suite_body(1, 0, b"tactile", b""), False),   # a suite without a case
    (_suite_body(1, 0, b"t" * 33, b"c"), False),   # a name over 32 bytes
    (_suite_body(1, 1, b"tactile", b"force")[:-1], False),  # shorter than it says
    (_task_body(2, 0x3D4CCCCD, b"N", []), True),
    (_task_body(4, 0, b"Hz", [0x42480000, 0x42C80000]), True),
    (_task_body(2, 0xBD4CCCCD, b"N", []), False),  # a negative tolerance
    (_task_body(2, 0x7F800000, b"N", []), False),  # an infinite one
    (_task_body(4, 0, b"Hz", [0x7FC00000]), False),  # a NaN class
    (_task_body(16, 0, b"", []), False),           # no such task id
    (_task_body(2, 0, b"N" * 9, []), False),       # a unit over 8 bytes
    (_task_body(4, 0, b"Hz", [0x42480000])[:-2], False),  # shorter than it says
])
def test_serial_suite_and_task_fields_are_checked(body: bytes, good: bool) -> None:
    dec = protocols.SerialDecoder()
    recs = dec.feed(framed(body)).records
    assert (dec.counters.frames_ok, dec.counters.malformed) == ((1, 0) if good else (0, 1))
    if good:
        assert isinstance(recs[0], (protocols.SuiteEntry, protocols.TaskEntry))
        for fd in (False, True):  # the same payload in CAN chunks gives the same record
            enc = protocols.CanEncoder(fd=fd)
            assert protocols.CanDecoder(fd=fd).feed(enc.session_record(recs[0])).records == recs


def test_a_board_without_a_suite_announces_none() -> None:
    config = BoardConfig(seed=2)
    link = GoldenLink(False)
    board = Board(config, lambda: link)
    board.warm_up()
    board.queue_session(protocols.SessionReason.START)
    link.tick = 0
    board.tick()
    recs = protocols.SerialDecoder().feed(b"".join(link.units)).records
    got = Announcement()
    assert any(got.take(r) for r in recs)
    assert got.as_dict()["suite"] is None and got.as_dict()["tasks"] == {}
