"""The touch-down/release rule (skinhil/receiver/touch_kind.py) on a simulated press, and the
reference answerer acting on it: a touch-down answered in full, a release without FORCE,
noise not at all."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import PtyPair

from protocols.events import EVENT_DTYPE
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.receiver.online import Prediction
from skinhil.receiver.scoring import ScoredDecision
from skinhil.receiver.task_answer import TaskAnswerer
from skinhil.receiver.touch_kind import KIND_S, RELEASE, TOUCH_DOWN, in_layer, touch_kind
from skinhil.transports.serial import SerialTransport
from skinhil.world import Contact, Indenter, Scene, TouchSensor, Trajectory, truth_records

DT = 1e-4
LOOKBACK_US = 3_000
"""The receiver's decision window starts this long before its onset's detection."""


def press(load_n: float) -> tuple[np.ndarray, int, int]:
    """The events of a noise-free default skin under a 3 mm sphere pressing ``load_n`` N for
    0.15 s, and the board times (µs) of its first and last touching ticks."""
    contact = Contact(Indenter("sphere", radius_m=3e-3),
                      Trajectory.press(0.0, 0.0, load_n, ramp_s=0.01, hold_s=0.15, load=True))
    touch = TouchSensor(SkinSensor(SkinModel(SkinParams()), DT, snr_db=math.inf),
                        Scene((contact,)))
    touch.start(0.0)
    n = int(round((contact.end_s + 0.1) / DT))
    _, spikes, raw = touch.advance_schedule(Schedule(()), n)
    truth = truth_records(raw, np.arange(n) * 100)
    touching = truth["t_us"][truth["nodes"] > 0]
    step, channel = np.nonzero(spikes)
    ev = np.zeros(step.shape[0], EVENT_DTYPE)
    ev["t"], ev["addr"] = step * 100, channel
    return ev, int(touching.min()), int(touching.max())


@pytest.fixture(scope="module")
def firm_press() -> tuple[np.ndarray, int, int]:
    return press(0.7)


def test_a_press_fires_in_layer_springs_and_its_release_the_between_layer_ones(
        firm_press: tuple[np.ndarray, int, int]) -> None:
    ev, down_us, up_us = firm_press
    mask = in_layer((6, 6))
    assert mask.sum() == 85 + 56 + 33 and mask.shape == (338,)
    assert touch_kind(ev["t"], ev["addr"], down_us, mask) == TOUCH_DOWN
    assert touch_kind(ev["t"], ev["addr"], up_us, mask) == RELEASE  # the rebound
    # the rule reads which springs fire: with the kinds swapped it calls them the other way
    assert touch_kind(ev["t"], ev["addr"], down_us, ~mask) == RELEASE
    assert touch_kind(ev["t"], ev["addr"], up_us, ~mask) == TOUCH_DOWN
    quiet = down_us - int(KIND_S * 1e6) - 1  # before the touch: no spike, neither
    assert touch_kind(ev["t"], ev["addr"], quiet, mask) is None
    # a lighter press's hold inhibits too little for a rebound without noise: no release
    light, _, light_up = press(0.4)
    assert touch_kind(light["t"], light["addr"], light_up, mask) is None


def decide(tasks: TaskAnswerer, ev: np.ndarray, start_us: int) -> None:
    """The receiver's decision for an onset whose window starts at ``start_us`` (µs), after
    the answerer saw the events up to its end."""
    end = start_us + 50_000
    seen = ev[ev["t"] < end]
    if seen.shape[0]:  # the receiver hands its listeners no empty batch
        tasks.on_events(seen, 0.0)
    p = Prediction(start_us + LOOKBACK_US, start_us, end, 0, (0.0,), 0.0)
    tasks.on_decision(ScoredDecision(p, None, None, None))


@pytest.mark.parametrize("at, answered", [
    ("touch-down", {"localisation": 1, "force": 1}),
    ("release", {"localisation": 1, "vibration": 1}),  # no FORCE: the object let go
    ("quiet", {}),                                      # neither: not answered
])
def test_the_reference_answers_a_touch_down_a_release_and_not_noise(
        firm_press: tuple[np.ndarray, int, int], pty_pair: PtyPair, at: str,
        answered: dict[str, int]) -> None:
    ev, down_us, up_us = firm_press
    start = {"touch-down": down_us, "release": up_us, "quiet": down_us - 60_000}[at]
    transport = SerialTransport(pty_pair.path, baud=921600)
    try:
        receiver = SimpleNamespace(transport=transport, board_id=0, session=None)
        tasks = TaskAnswerer(receiver)  # type: ignore[arg-type]
        decide(tasks, ev, start)
    finally:
        transport.shutdown()
    assert dict(tasks.sent) == answered
