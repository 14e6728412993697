"""A suite case played off the clock (as ``serve --suite SUITE:CASE --seed N --score`` plays
it, tick by tick over :class:`~harness.golden.GoldenLink`) against a host that answers
through the wire: a script of commands at given ticks (a decoder that reads nothing), or
listeners fed the board's stream as it leaves (the reference receiver's answerers, the grip
controller), whose commands arrive at the board's next tick.

The board decodes and scores every command as it does on any link; what comes back is what
the score file holds (the DECISION scoreboard, ``tasks``, ``grasp``), so a scripted decoder and a
baseline are scored by one path.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import protocols
from firmware_sim.board import Board, BoardConfig
from firmware_sim.score import board_score
from harness.golden import GoldenLink, _plain
from skinhil.cli.serve import write_truth
from skinhil.decoding.classifier import DirectionDecoder
from skinhil.model.timeline import Timeline
from skinhil.receiver.online import WindowDecoder
from skinhil.receiver.receiver import Receiver, ReceiverListener
from skinhil.receiver.training import feature_spec
from skinhil.suites import Trials, suite_trials
from skinhil.transports.base import Transport

SNR_DB = 10.0
"""``serve``'s default neuron noise (dB)."""
TICK_S = 1e-3
"""``serve``'s default tick (s)."""

Script = dict[int, list[Any]]
"""Host commands (``protocols`` records) by the tick they arrive at."""


def tick_of(t_s: float) -> int:
    """The tick (of :data:`TICK_S`) at board time ``t_s`` (s)."""
    return int(round(t_s / TICK_S))


class HostEnd(Transport[Any]):
    """The host's end of a :class:`GoldenLink`: what a host sends reaches the board at the
    link's next tick; it receives nothing by itself (the player feeds it)."""

    scheme = "golden-host"

    def __init__(self, link: GoldenLink) -> None:
        self.link = link
        self.kind = link.kind
        self.carries_frames = link.carries_frames
        self.unit = link.unit
        self.can_fd = link.can_fd

    @property
    def name(self) -> str:
        return f"{self.link.name}-host"

    def send(self, payload: Any, timeout: float | None = None) -> int:
        unit = list(payload) if self.carries_frames else bytes(payload)
        self.link.script.setdefault(self.link.tick + 1, []).append(unit)
        return len(payload)

    def recv(self, timeout: float | None = None) -> Any:
        return self.empty()

    def wire_seconds(self, payload: Any) -> float:
        return self.link.wire_seconds(payload)

    def empty(self) -> Any:
        return self.link.empty()

    def shutdown(self) -> None:
        pass


Listening = Callable[[HostEnd], Iterable[Any]]
"""Builds the host's readers of the stream on its end of the link: each has
``feed(payload, host_s)`` (a :class:`Receiver`, a :class:`GripLoop`)."""


@dataclass
class Played:
    """A played case: its trials and what the score file holds."""

    trials: Trials
    scores: dict[str, Any]
    """The run's score file (``serve --score``: :func:`firmware_sim.score.board_score`)."""
    truth: str
    """The run's truth file (``serve --truth``: markers and trials, JSON lines)."""

    def task(self, name: str) -> dict[str, Any]:
        """The score file's ``tasks.<name>``; ``classification`` is the DECISION
        scoreboard's, at the score file's top level (SPEC.md §3.5.2)."""
        if name == "classification":
            return {k: v for k, v in self.scores.items() if k not in ("tasks", "grasp")}
        return dict(self.scores["tasks"][name])

    def score(self, name: str) -> float:
        """The headline ``score`` of task ``name`` (``grasp``: ``grasp.score``); 0 where
        none was scored (no trial and no answer)."""
        d = self.scores["grasp"] if name == "grasp" else self.task(name)
        return float(d["score"] or 0.0)


def play_case(ref: str, seed: int, script: Script | None = None,
              listening: Listening | None = None, frames: bool = False) -> Played:
    """Play case ``ref`` (``SUITE:CASE``) of ``seed`` to its end, as ``serve --suite ref
    --seed seed --score`` does (no truth markers on the link), with the host's ``script``
    and/or the readers ``listening`` builds; the scores of the score file."""
    trials = suite_trials(ref, seed)
    config = BoardConfig(seed=seed, snr_db=SNR_DB, tick_s=TICK_S,
                         schedule_mode=Timeline.SCHEDULE_FILE, markers=False,
                         tasks=tuple(t.name for t in trials.tasks))
    link = GoldenLink(frames)
    encoder = link.codec_pair(board_id=config.board_id)[0]
    for k, cmds in (script or {}).items():
        link.script.setdefault(k, []).extend(encoder.command(c) for c in cmds)
    board = Board(config, lambda: link, trials.scenario.schedule, None,
                  trials.scenario.scene, trials.grasp)
    readers = list(listening(HostEnd(link))) if listening is not None else []
    board.warm_up()
    board.queue_session(protocols.SessionReason.START)
    seen = 0
    for k in range(tick_of(trials.duration_s)):
        link.tick = k
        board.tick()
        payload = _units(link, seen)
        seen = len(link.units)
        for reader in readers:
            reader.feed(payload, k * TICK_S)
    board.finish(protocols.RunEndReason.DURATION)
    for reader in readers:
        reader.feed(_units(link, seen), tick_of(trials.duration_s) * TICK_S)
    scores = board_score(board)
    with tempfile.TemporaryDirectory() as tmp:
        write_truth(Path(tmp) / "truth.jsonl", board)
        truth = (Path(tmp) / "truth.jsonl").read_text(encoding="utf-8")
    return Played(trials, json.loads(json.dumps(scores, default=_plain)), truth)


def _units(link: GoldenLink, since: int) -> Any:
    new = link.units[since:]
    return list(new) if link.carries_frames else b"".join(new)


def no_skill_decoder(seed: int = 0) -> WindowDecoder:
    """A stimulus decoder of no skill (fitted on random features in the receiver's layout):
    the random answerer reads only the onsets the receiver detects, never its classes."""
    spec = feature_spec()
    rng = np.random.default_rng(seed)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    return WindowDecoder(DirectionDecoder(spec).fit(x, y))


def receiver_with(end: HostEnd, *make: Callable[[Receiver], ReceiverListener]) -> Receiver:
    """A reference receiver on ``end`` (a no-skill stimulus decoder) with the listeners
    ``make`` builds on it (``TaskAnswerer``, ``DecisionAnswerer``)."""
    receiver = Receiver(end, no_skill_decoder())
    for m in make:
        receiver.add_listener(m(receiver))
    return receiver
