"""Scoring the receiver's decisions against the board's ground-truth markers, online and
offline, by the matching rule of :mod:`skinhil.scoring.matching`.

A marker says stimulus ``stimulus_id`` started at board time ``t_us``. The receiver matches
each decision at its **decision time** (``decided_t_us``: the end of its decision window, the
board time the decision needed; the board matches a DECISION at its arrival, which is later
by the link alone) with a window of ``match_window_s`` plus the decision window (an onset
detected at most ``match_window_s`` after the marker):

- matched to an onset without a decision: scored (confusion, latency);
- anything else (a duplicate, a late or a stimulus-less detection) is a **false alarm**:
  counted and reported, not in the accuracy (it has no true class); in training it gives
  no window;
- an onset marker still without a decision once board time has passed
  ``t + match_window + decision window`` is a **miss** and counts as a wrong decision;
- **accuracy** = correct decisions / scored markers (matched + missed).

Offline training (:mod:`skinhil.receiver.training`) applies the same rule to the windows
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
from skinhil.scoring.matching import MatchKind, Onset, OnsetMatcher


@dataclass
class ScoredDecision:
    """A decision and, when matched, its true class and latencies (s)."""

    prediction: Prediction
    true_label: int | None
    latency_board_s: float | None
    latency_host_s: float | None
    onset_t_us: int | None = None
    """Board time (µs) of the onset it was matched to (None for a false alarm)."""

    @property
    def correct(self) -> bool | None:
        """True/False when matched to a marker, None for a false alarm."""
        return None if self.true_label is None else self.true_label == self.prediction.label


@dataclass
class Scoreboard:
    """Running accuracy, confusion matrix, misses, false alarms and decision latencies."""

    classes: tuple[int, ...]
    match_window_us: int
    decisions: list[ScoredDecision] = field(default_factory=list)
    false_alarms: int = 0
    unknown_class_markers: int = 0

    def __post_init__(self) -> None:
        n = len(self.classes)
        self.confusion = np.zeros((n, n), dtype=np.int64)
        """Rows: true class, columns: predicted class (order of ``classes``)."""
        self._index = {c: i for i, c in enumerate(self.classes)}
        self.matcher = OnsetMatcher(self.match_window_us)
        """The onsets and the matching rule (:mod:`skinhil.scoring.matching`)."""

    def add_marker(self, t_us: int, stimulus_id: int) -> None:
        """Record a ground-truth onset marker."""
        if stimulus_id not in self._index:
            self.unknown_class_markers += 1
            return
        self.matcher.add_onset(t_us, stimulus_id)

    def claim(self, decided_t_us: int) -> Onset | None:
        """Match a decision made at board time ``decided_t_us`` (µs) to an onset (see the
        module rule): the onset, now taken; None for a false alarm (counted)."""
        m = self.matcher.match(decided_t_us)
        if m.kind is MatchKind.MATCHED:
            return m.onset
        self.false_alarms += 1
        return None

    def add_prediction(self, pred: Prediction,
                       to_host_s: Callable[[int], float | None] | None = None) -> ScoredDecision:
        """Score one decision; ``to_host_s`` maps a board time (µs) to host time (s)."""
        onset = self.claim(pred.decided_t_us)
        if onset is None:
            scored = ScoredDecision(pred, None, None, None)
        else:
            t, sid = onset.t_us, onset.stimulus_id
            onset_host = None if to_host_s is None else to_host_s(t)
            lat_host = None if onset_host is None else pred.host_time_s - onset_host
            scored = ScoredDecision(pred, sid, (pred.decided_t_us - t) * 1e-6, lat_host,
                                    onset_t_us=t)
            if pred.label in self._index:
                self.confusion[self._index[sid], self._index[pred.label]] += 1
        self.decisions.append(scored)
        return scored

    def resolve(self, board_time_us: int) -> int:
        """Count markers whose match window has passed without a decision; return new misses."""
        return self.matcher.resolve(board_time_us)

    @property
    def misses(self) -> int:
        """Onset markers that got no decision in their window."""
        return self.matcher.misses

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
    """The scoreboard of a stream cut into ``windows``: decisions matched at their decision
    time within ``match_window_s`` plus the window's length."""
    return Scoreboard(tuple(int(c) for c in classes),
                      int(round(match_window_s * 1e6)) + windows.window_steps * windows.dt_us)
