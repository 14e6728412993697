"""The reference receiver's task decoders (skinhil/receiver/task_decoders.py) on spikes whose
answer is known: a centroid, the vibration class of phase-locked spikes, the force line, the
slip rule."""

from __future__ import annotations

import math
import os
import select
import time
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import PtyPair

import protocols
from protocols import Task
from skinhil.events import make_events
from skinhil.receiver.answer import CommandSender
from skinhil.receiver.task_answer import TaskAnswerer
from skinhil.receiver.task_decoders import (
    SLIP_CHANNELS,
    SLIP_SPIKES,
    SLIP_WATCH_S,
    SLIP_WINDOW_S,
    TOUCH_SPIKES_S,
    VIBRATION_CLASSES_HZ,
    force_n,
    frequency_hz,
    sensor_xy_mm,
    slip_time_us,
    touch_spikes,
    vibration_features,
    within_touch,
)
from skinhil.transports.serial import SerialTransport


def test_a_touch_is_the_trimmed_centroid_and_count_of_its_early_spikes() -> None:
    xy = sensor_xy_mm((6, 6))
    assert xy.shape == (338, 2) and np.allclose(xy.mean(axis=0), 0.0, atol=1e-9)
    rng = np.random.default_rng(0)
    start = 1_000_000
    near = np.flatnonzero(np.hypot(xy[:, 0] - 1.0, xy[:, 1] + 1.0) < 0.8)
    far = np.flatnonzero((xy[:, 0] < -1.5) & (xy[:, 1] > 1.0))  # noise, 3 mm away and more
    early = int(TOUCH_SPIKES_S * 1e6)
    t = np.concatenate([start + rng.integers(0, early, near.shape[0]),
                        start + rng.integers(0, early, 4),       # noise within the burst
                        start + early + rng.integers(0, 30_000, 40)])  # noise after it
    addr = np.concatenate([near, rng.choice(far, 4), rng.integers(0, 338, 40)])
    (x, y), spikes = touch_spikes(t, addr, start, xy)
    assert abs(x - 1.0) < 0.3 and abs(y + 1.0) < 0.3
    assert spikes == near.shape[0]  # neither the far nor the late spikes
    everything = xy[addr].mean(axis=0)  # the centroid of all of them: pulled away
    assert math.hypot(everything[0] - 1.0, everything[1] + 1.0) > 0.5
    assert touch_spikes(t, addr, start + 10**6, xy) == ((0.0, 0.0), 0)


def test_frequency_classes_spikes_by_their_phase_locking() -> None:
    rng = np.random.default_rng(0)
    for hz in (50.0, 100.0):  # 170 spikes over 0.3 s, the touched channels' locked to hz
        locked = (np.arange(60) + rng.normal(0, 0.03, 60)) / hz * 1e6 % 3e5
        t_us = np.concatenate([locked, rng.uniform(0, 3e5, 110)])
        addr = np.concatenate([rng.integers(0, 10, 60), rng.integers(10, 338, 110)])
        order = np.argsort(t_us)
        features = vibration_features(t_us[order].astype(np.int64), addr[order])
        assert features[0] == 170 and features[1 + VIBRATION_CLASSES_HZ.index(hz)] > 10
        assert frequency_hz(t_us[order].astype(np.int64), addr[order]) == hz


def test_force_is_a_line_of_spikes_and_a_slip_needs_its_channels() -> None:
    assert force_n(10) != force_n(30) and min(force_n(0), force_n(10**6)) >= 0.0
    assert not within_touch(100_000, None)
    assert within_touch(300_000, 100_000) and not within_touch(700_000, 100_000)
    start = 1_000_000
    lo = start + int(SLIP_WATCH_S[0] * 1e6)
    burst = lo + 20_000 + np.arange(SLIP_SPIKES) * 5_000  # within SLIP_WINDOW_S
    slip_ch = np.resize(np.asarray(SLIP_CHANNELS), SLIP_SPIKES)
    other = next(c for c in range(338) if c not in SLIP_CHANNELS)
    assert slip_time_us(burst, slip_ch, start) == burst[-1]
    assert slip_time_us(burst, np.full(SLIP_SPIKES, other), start) is None
    assert slip_time_us(burst[:-1], slip_ch[:-1], start) is None  # one spike short
    spread = lo + np.arange(SLIP_SPIKES) * int(SLIP_WINDOW_S * 1e6) // (SLIP_SPIKES - 2)
    assert slip_time_us(spread, slip_ch, start) is None  # too slow for a slip
    assert slip_time_us(burst - 100_000, slip_ch, start) is None  # the touch-down's burst


def test_task_answers_leave_through_the_command_sender_within_the_wire_range(
        pty_pair: PtyPair) -> None:
    transport = SerialTransport(pty_pair.path, baud=921600)
    try:
        decisions = CommandSender(transport, 0)
        receiver = SimpleNamespace(transport=transport, board_id=0, session=None)
        tasks = TaskAnswerer(receiver, "random", encoder=decisions.encoder)  # type: ignore[arg-type]
        tasks._send(Task.FORCE, (1e9,))         # beyond the wire: its greatest value
        tasks._send(Task.FORCE, (math.nan,))    # not a number: not sent
        tasks._send(Task.LOCALISATION, (-500.0, 1.25))
        decisions.send(protocols.Decision(7, 3), "DECISION")
        got: list = []
        decoder = protocols.SerialDecoder()
        end = time.monotonic() + 5.0
        while len(got) < 3 and time.monotonic() < end:
            if select.select([pty_pair.master], [], [], 0.2)[0]:
                got += decoder.feed(os.read(pty_pair.master, 4096)).records
    finally:
        transport.shutdown()
    assert [type(r).__name__ for r in got] == ["Answer", "Answer", "Decision"]
    assert got[0].values == pytest.approx((protocols.answer_range(Task.FORCE)[1],))
    assert got[1].values == pytest.approx((protocols.answer_range(Task.LOCALISATION)[0], 1.25))
    assert tasks.as_dict()["sent"] == {"force": 1, "localisation": 1}
    assert tasks.invalid == 1 and tasks.sender.sent == 2 and decisions.sent == 1
    assert tasks.sender.encoder is decisions.encoder  # one sequence count on the link


def test_an_empty_batch_of_events_answers_nothing(pty_pair: PtyPair) -> None:
    transport = SerialTransport(pty_pair.path, baud=921600)
    try:
        receiver = SimpleNamespace(transport=transport, board_id=0, session=None)
        tasks = TaskAnswerer(receiver)  # type: ignore[arg-type]
        tasks.on_events(make_events(np.zeros(0), np.zeros(0)), 0.0)
    finally:
        transport.shutdown()
    assert dict(tasks.sent) == {}


def test_the_tasks_the_session_announces_are_the_only_ones_answered(pty_pair: PtyPair) -> None:
    """A SESSION that announces its tasks (bit n for Task n) switches the others off before
    any ANSWER; one that announces none (an earlier board) leaves every task on."""
    transport = SerialTransport(pty_pair.path, baud=921600)
    try:
        receiver = SimpleNamespace(transport=transport, board_id=0, session=None)
        tasks = TaskAnswerer(receiver, "random")  # type: ignore[arg-type]
        tasks.on_session(SimpleNamespace(rows=6, cols=6, tasks=0))
        assert tasks.off == set()
        tasks.on_session(SimpleNamespace(rows=6, cols=6,
                                         tasks=1 << Task.FORCE | 1 << Task.SLIP))
        for task, values in ((Task.FORCE, (0.3,)), (Task.LOCALISATION, (0.0, 0.0)),
                             (Task.SLIP, ()), (Task.VIBRATION, (100.0,))):
            tasks._send(task, values)
    finally:
        transport.shutdown()
    assert tasks.off == {Task.CLASSIFICATION, Task.LOCALISATION, Task.VIBRATION}
    assert tasks.as_dict()["sent"] == {"force": 1, "slip": 1}
