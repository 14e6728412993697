"""The reference receiver answers the contact tasks (``skinhil listen --answer``): at each
onset it detects (no ground truth) it reads which springs the onset's burst excites
(:mod:`skinhil.receiver.touch_kind`). At a touch-down it sends ANSWERs (``protocols/SPEC.md``
§3.5.3) of LOCALISATION and FORCE at the end of the decision window, VIBRATION once the
touch's vibration window has passed, and a SLIP as soon as the touch's spikes show it
(within its slip watch), computed by :mod:`skinhil.receiver.task_decoders` from the spikes;
an onset inside the touch after it is no new touch. At a release outside a touch (a
touch whose touch-down went unseen) it sends LOCALISATION, from the release's burst, and
VIBRATION, from the spikes of the vibration window before it (the touch was held then),
and no FORCE (the object has let go). An onset that is neither (noise) is not answered.

Two bounds to compare it with, through the same link and the same answer path:

- ``random``: the same onsets and the same tasks at each, each value drawn at random (a
  place on the skin, a force of 0.05..0.6 N, a frequency of the vibration band), a slip with
  p = 0.5 at a random time of the touch's slip watch;
- ``oracle``: the truth of an earlier run of the same scenario (``serve --truth FILE``, the
  world's mechanics do not depend on the noise): each trial answered with its true values
  :data:`ORACLE_DELAY_S` after its onset, timed by the board time the stream shows.

A task the SESSION does not announce (its ``tasks`` bitmask, SPEC §3.7) is not answered;
from a board that announces none (an earlier revision), a task it NACKs as TASK_NOT_POSED is
not answered again.
"""

from __future__ import annotations

import json
import logging
import math
from collections import Counter, deque
from pathlib import Path
from typing import Any

import numpy as np

import protocols
from skinhil.errors import ConfigError
from skinhil.receiver.answer import CommandSender
from skinhil.receiver.receiver import Receiver, ReceiverListener
from skinhil.receiver.scoring import ScoredDecision
from skinhil.receiver.task_decoders import (
    SLIP_WATCH_S,
    VIBRATION_BAND_HZ,
    VIBRATION_WINDOW_S,
    force_n,
    frequency_hz,
    sensor_xy_mm,
    slip_time_us,
    touch_spikes,
    within_touch,
)
from skinhil.receiver.touch_kind import RELEASE, TOUCH_DOWN, in_layer, touch_kind
from skinhil.tasks import registry

log = logging.getLogger(__name__)

ANSWERERS = ("reference", "random", "oracle")
"""Who answers the tasks (``listen --answer-with``)."""
ORACLE_DELAY_S = 0.05
"""The oracle answers each trial this long (s) after its onset: the reference's window."""
KEEP_EVENTS_S = 1.0
"""Events kept for the next decision window (s of board time)."""


class TaskAnswerer(ReceiverListener):
    """Sends ANSWERs of the contact tasks for ``receiver``'s detected onsets (``reference``
    or ``random``) or from a truth file (``oracle``, ``truth_path``), through its
    :class:`CommandSender`; ``encoder`` the host's encoder when another listener sends
    commands on the link too (a :class:`~skinhil.receiver.answer.DecisionAnswerer`'s)."""

    def __init__(self, receiver: Receiver, answerer: str = "reference",
                 truth_path: Path | None = None, seed: int = 0, encoder: Any = None) -> None:
        if answerer not in ANSWERERS:
            raise ConfigError(f"answerer {answerer!r}: give one of {', '.join(ANSWERERS)}")
        if (answerer == "oracle") != (truth_path is not None):
            raise ConfigError("the oracle answers from a truth file (serve --truth FILE): "
                              "give both, or neither")
        self.receiver = receiver
        self.answerer = answerer
        self.sender = CommandSender(receiver.transport, receiver.board_id, encoder)
        """Sends the ANSWERs and counts them in all (the per-task counts are here); its
        encoder shared with a DecisionAnswerer on the same link (SPEC.md §3.5)."""
        self._rng = np.random.default_rng(seed)
        self._events: deque[np.ndarray] = deque()
        self._xy_mm: np.ndarray | None = None
        self._touch_us: int | None = None
        self._vibration: deque[int] = deque()
        """Onsets (µs) whose VIBRATION answer waits for its window's spikes."""
        self._slip_watch: tuple[int, int | None] | None = None
        """The touch watched for a slip: its window start (µs) and, for ``random``, the
        board time (µs) its SLIP is due (None: none)."""
        self._token = 0
        self._pending: dict[int, int] = {}
        """token → task of the ANSWERs not yet ACKed."""
        self.off: set[int] = set()
        """Tasks the board does not pose (not in the SESSION's tasks, or NACKed
        TASK_NOT_POSED): not answered."""
        self.sent: Counter[str] = Counter()
        self.acked: Counter[str] = Counter()
        self.nacked: Counter[str] = Counter()
        self.invalid = 0
        """Answers not sent because a value was not a finite number."""
        self._oracle: list[tuple[int, int, tuple[float, ...]]] = (
            _oracle_answers(truth_path) if truth_path is not None else [])

    # -- listener -------------------------------------------------------------------------
    def on_session(self, session: Any) -> None:
        if session.rows and session.cols:
            self._xy_mm = sensor_xy_mm((int(session.rows), int(session.cols)))
        if session.tasks:  # the board says which tasks it scores
            self.off = {t for t in protocols.Task if not session.tasks >> t & 1}

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        if self.answerer == "oracle":
            self._play_oracle()
            return
        if events.shape[0] == 0:
            return
        self._events.append(events)
        last = int(events["t"][-1])
        while len(self._events) > 1 and int(self._events[0]["t"][-1]) < last - KEEP_EVENTS_S * 1e6:
            self._events.popleft()
        window_us = int(VIBRATION_WINDOW_S * 1e6)
        while self._vibration and self._vibration[0] + window_us <= last:
            t0 = self._vibration.popleft()
            ev = self._window(t0, t0 + window_us)
            hz = (frequency_hz(ev["t"], ev["addr"]) if self.answerer == "reference"
                  else float(self._rng.uniform(*VIBRATION_BAND_HZ)))
            self._send(protocols.Task.VIBRATION, (round(hz, 2),))
        self._watch_slip(last)

    def on_status(self, status: Any) -> None:
        if self.answerer == "oracle":
            self._play_oracle()

    def on_decision(self, decision: ScoredDecision) -> None:
        if self.answerer == "oracle":
            return
        p = decision.prediction
        if within_touch(p.detect_t_us, self._touch_us):
            return
        ev = self._window(p.window_t_us, p.decided_t_us)
        kind = touch_kind(ev["t"], ev["addr"], p.window_t_us, in_layer(self._size()))
        if kind == RELEASE:
            self._answer_release(p.window_t_us, ev)
        if kind != TOUCH_DOWN:
            return
        self._touch_us = p.detect_t_us
        lo, hi = (p.window_t_us + int(s * 1e6) for s in SLIP_WATCH_S)
        due = (None if self.answerer == "reference" or self._rng.random() >= 0.5
               else int(self._rng.integers(lo, hi)))
        if self.answerer == "reference" or due is not None:
            self._slip_watch = (p.window_t_us, due)
        if self.answerer == "reference":
            centre, spikes = touch_spikes(ev["t"], ev["addr"], p.window_t_us, self._xy())
            values = {protocols.Task.LOCALISATION: centre,
                      protocols.Task.FORCE: (force_n(spikes),)}
        else:
            values = {protocols.Task.LOCALISATION: self._random_place(),
                      protocols.Task.FORCE: (float(self._rng.uniform(0.05, 0.6)),)}
        for task, vals in values.items():
            self._send(task, tuple(round(v, 3) for v in vals))
        if protocols.Task.VIBRATION not in self.off:
            self._vibration.append(p.window_t_us)

    def _answer_release(self, start_us: int, ev: np.ndarray) -> None:
        """A release at a decision window starting at ``start_us`` (µs; its events ``ev``)
        ends a touch whose touch-down went unseen: its place from the release's burst, its
        vibration from the :data:`VIBRATION_WINDOW_S` before it."""
        window_us = int(VIBRATION_WINDOW_S * 1e6)
        held = self._window(start_us - window_us, start_us)
        if self.answerer == "reference":
            place = touch_spikes(ev["t"], ev["addr"], start_us, self._xy())[0]
            hz = frequency_hz(held["t"], held["addr"])
        else:
            place = self._random_place()
            hz = float(self._rng.uniform(*VIBRATION_BAND_HZ))
        self._send(protocols.Task.LOCALISATION, tuple(round(v, 3) for v in place))
        self._send(protocols.Task.VIBRATION, (round(hz, 2),))

    def on_ack(self, ack: Any) -> None:
        if ack.opcode != protocols.CommandCode.ANSWER or ack.token not in self._pending:
            return
        task = self._pending.pop(ack.token)
        self.sender.count_ack(ack)
        name = protocols.Task(task).name.lower()
        if ack.ok:
            self.acked[name] += 1
        else:
            self.nacked[name] += 1
            if ack.reason == protocols.NackReason.TASK_NOT_POSED:
                self.off.add(task)

    # -- helpers --------------------------------------------------------------------------
    def _size(self) -> tuple[int, int]:
        s = self.receiver.session
        return (int(s.rows), int(s.cols)) if s is not None and s.rows else (6, 6)

    def _xy(self) -> np.ndarray:
        return self._xy_mm if self._xy_mm is not None else sensor_xy_mm(self._size())

    def _random_place(self) -> tuple[float, float]:
        rows, cols = self._size()
        return (float(self._rng.uniform(-(cols - 1) / 2, (cols - 1) / 2)),
                float(self._rng.uniform(-(rows - 1) / 2, (rows - 1) / 2)))

    def _window(self, start_us: int, end_us: int) -> np.ndarray:
        if not self._events:
            return np.zeros(0, dtype=[("t", "<i8"), ("addr", "<u2")])
        ev = np.concatenate(list(self._events))
        return ev[(ev["t"] >= start_us) & (ev["t"] < end_us)]

    def _watch_slip(self, last_us: int) -> None:
        """Answer SLIP for the watched touch once its spikes up to ``last_us`` (µs) show it
        (``random``: once its due time passed); stop watching at the watch's end."""
        if self._slip_watch is None or protocols.Task.SLIP in self.off:
            return
        start, due = self._slip_watch
        end = start + int(SLIP_WATCH_S[1] * 1e6)
        if due is not None:
            slipped = due <= last_us
        else:
            ev = self._window(start, min(end, last_us + 1))
            slipped = slip_time_us(ev["t"], ev["addr"], start) is not None
        if slipped:
            self._send(protocols.Task.SLIP, ())
        if slipped or last_us >= end:
            self._slip_watch = None

    def _play_oracle(self) -> None:
        now = self.receiver.known_board_time_us()
        while self._oracle and self._oracle[0][0] <= now:
            _, task, values = self._oracle.pop(0)
            self._send(protocols.Task(task), values)

    def _send(self, task: protocols.Task, values: tuple[float, ...]) -> None:
        if task in self.off:
            return
        if not all(math.isfinite(v) for v in values):
            log.warning("ANSWER of %s not sent: a value is not a number: %r", task.name, values)
            self.invalid += 1
            return
        if values:  # within what the wire carries (SPEC.md §3.5.3): the nearest it can
            lo, hi = protocols.answer_range(task)
            values = tuple(min(max(v, lo), hi) for v in values)
        self._token = (self._token + 1) % 65536
        if self.sender.send(protocols.Answer(self._token, task, values),
                            f"ANSWER of {task.name}"):
            self._pending[self._token] = int(task)
            self.sent[task.name.lower()] += 1

    def as_dict(self) -> dict[str, Any]:
        """The answers per task: sent, acked, nacked; how many the link refused (unsent) and
        how many had a value that is not a number (invalid)."""
        return {"answerer": self.answerer, "sent": dict(self.sent), "acked": dict(self.acked),
                "nacked": dict(self.nacked), "unsent": self.sender.unsent,
                "invalid": self.invalid}


def _oracle_answers(path: Path) -> list[tuple[int, int, tuple[float, ...]]]:
    """(due board time µs, task, values) of every trial of a ``serve --truth`` file, in
    time order."""
    out = []
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ConfigError(f"cannot read the truth file {path}: {exc.strerror}") from None
    for i, line in enumerate(lines, 1):
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            raise ConfigError(f"{path}: line {i} is not JSON: give a serve --truth file") \
                from None
        if row.get("type") != "trial":
            continue
        task = registry.by_name(str(row["task"]))
        if any(row.get(k) is None for k in task.truth):
            continue
        out.append((int(row["t_us"]) + int(ORACLE_DELAY_S * 1e6), task.wire_id,
                    task.oracle_values(row)))
    return sorted(out)
