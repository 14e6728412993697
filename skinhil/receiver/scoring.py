"""Scoring decisions against the board's ground-truth markers — one rule, online and offline.

A marker says stimulus ``stimulus_id`` started at board time ``t_us``. The rule:

- a detection (decision) is matched to the latest onset marker at or before its detection
  time, if the detection is at most ``match_window_s`` after it and that marker has no
  decision yet (each marker is matched at most once, to its first decision);
- a decision matched to no marker is a **false alarm**: counted and reported, not in the
  accuracy (it has no true class); in training it gives no window;
- an onset marker still without a decision once board time has passed
  ``t + match_window + resolve_lag`` (``resolve_lag``: the decision window's length, so a
  late detection's decision can still arrive) is a **miss** and counts as a wrong decision;
- **accuracy** = correct decisions / scored markers (matched + missed).

Offline training (:mod:`skinhil.receiver.training`) applies the same rule to the detections
on its simulated stream: its accuracy is the cross-validated window accuracy times the
fraction of markers matched, the same definition as online.

Decision latency is the board time from the marker's onset to the end of the decision
window (what the decision had to wait for), and the host-side latency adds the link and
processing: host time of the decision minus the host time at which the board was at the
onset (estimated by the board clock).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from skinhil.receiver.online import OnsetWindows, Prediction


@dataclass
class ScoredDecision:
    """A decision and, when matched, its true class and latencies (s)."""

    prediction: Prediction
    true_label: int | None
    latency_board_s: float | None
    latency_host_s: float | None

    @property
    def correct(self) -> bool | None:
        """True/False when matched to a marker, None for a false alarm."""
        return None if self.true_label is None else self.true_label == self.prediction.label


@dataclass
class Scoreboard:
    """Running accuracy, confusion matrix, misses, false alarms and decision latencies."""

    classes: tuple[int, ...]
    match_window_us: int
    resolve_lag_us: int = 0
    """Extra board time (µs) after the match window before an undecided marker is a miss."""
    markers: list[tuple[int, int]] = field(default_factory=list)
    """Onset markers seen: (t_us, stimulus_id)."""
    decided: set[int] = field(default_factory=set)
    """Indices into ``markers`` that have a decision."""
    decisions: list[ScoredDecision] = field(default_factory=list)
    misses: int = 0
    false_alarms: int = 0
    unknown_class_markers: int = 0
    _resolved_upto: int = 0

    def __post_init__(self) -> None:
        n = len(self.classes)
        self.confusion = np.zeros((n, n), dtype=np.int64)
        """Rows: true class, columns: predicted class (order of ``classes``)."""
        self._index = {c: i for i, c in enumerate(self.classes)}

    def add_marker(self, t_us: int, stimulus_id: int) -> None:
        """Record a ground-truth onset marker."""
        if stimulus_id not in self._index:
            self.unknown_class_markers += 1
            return
        self.markers.append((int(t_us), int(stimulus_id)))

    def claim(self, detect_t_us: int) -> int | None:
        """Match a detection at board time ``detect_t_us`` (µs) to a marker (see the module
        rule): the marker's index, now taken; None for a false alarm (counted)."""
        for i in range(len(self.markers) - 1, -1, -1):
            t, _ = self.markers[i]
            if t <= detect_t_us:
                if detect_t_us - t <= self.match_window_us and i not in self.decided:
                    self.decided.add(i)
                    return i
                break
        self.false_alarms += 1
        return None

    def add_prediction(self, pred: Prediction,
                       to_host_s: Callable[[int], float | None] | None = None) -> ScoredDecision:
        """Score one decision; ``to_host_s`` maps a board time (µs) to host time (s)."""
        match = self.claim(pred.detect_t_us)
        if match is None:
            scored = ScoredDecision(pred, None, None, None)
        else:
            t, sid = self.markers[match]
            onset_host = None if to_host_s is None else to_host_s(t)
            lat_host = None if onset_host is None else pred.host_time_s - onset_host
            scored = ScoredDecision(pred, sid, (pred.decided_t_us - t) * 1e-6, lat_host)
            if pred.label in self._index:
                self.confusion[self._index[sid], self._index[pred.label]] += 1
        self.decisions.append(scored)
        return scored

    def resolve(self, board_time_us: int) -> int:
        """Count markers whose match window has passed without a decision; return new misses."""
        new = 0
        while self._resolved_upto < len(self.markers):
            t, _ = self.markers[self._resolved_upto]
            if t + self.match_window_us + self.resolve_lag_us > board_time_us:
                break
            if self._resolved_upto not in self.decided:
                new += 1
            self._resolved_upto += 1
        self.misses += new
        return new

    @property
    def scored(self) -> int:
        """Markers with a decision or a miss."""
        return int(self.confusion.sum()) + self.misses

    @property
    def correct(self) -> int:
        return int(np.trace(self.confusion))

    @property
    def accuracy(self) -> float:
        """Correct decisions / scored markers (misses count as wrong); nan before any."""
        return self.correct / self.scored if self.scored else float("nan")

    def latencies_s(self, host: bool = False) -> np.ndarray:
        """Decision latencies (s) of the matched decisions, board time or host time."""
        vals = [d.latency_host_s if host else d.latency_board_s for d in self.decisions
                if d.true_label is not None]
        return np.array([v for v in vals if v is not None], dtype=float)


def scoreboard_for(classes: tuple[int, ...], windows: OnsetWindows,
                   match_window_s: float) -> Scoreboard:
    """The scoreboard of a stream cut into ``windows`` (its window length is the lag)."""
    return Scoreboard(tuple(int(c) for c in classes), int(round(match_window_s * 1e6)),
                      windows.window_steps * windows.dt_us)
