"""The board's scoreboard of a decoder under test: its DECISIONs against the ground truth.

Public API (the board calls it live; a replay of a recording can call it the same way):

- :meth:`DecisionScoreboard.onset` — a stimulus started (``stimulus_id``, board time µs);
- :meth:`DecisionScoreboard.decision` — a DECISION arrived (board time µs): its
  :class:`Outcome`, which is also counted;
- :meth:`DecisionScoreboard.advance` — board time moved on: onsets whose response window
  passed without a decision become misses;
- :meth:`DecisionScoreboard.summary` — everything as a plain dict (JSON-ready).

Matching follows :mod:`skinhil.scoring.matching` (``protocols/SPEC.md`` §3.5.2). Every
decision lands in exactly one outcome counter, so ``decisions == sum of the outcomes``;
every onset is matched, missed or still pending.
"""

from __future__ import annotations

import enum
import math
from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np

import protocols
from skinhil.errors import ConfigError
from skinhil.scoring.headline import HedgedTrials, headline
from skinhil.scoring.matching import MatchKind, OnsetMatcher


class Outcome(enum.Enum):
    """Where one DECISION lands on the scoreboard (the value is its counter's name)."""

    RIGHT = "right"
    """Matched to an onset of the stimulus it names."""
    WRONG = "wrong"
    """Matched to an onset of another stimulus."""
    DUPLICATE = "duplicates"
    """Within the window of an onset that already has a decision."""
    LATE = "late"
    """After the window of the latest onset, which got no decision (that onset is a miss)."""
    FALSE_ALARM = "false_alarms"
    """No onset before it, or after the window of an onset that was decided."""
    WHILE_STOPPED = "while_stopped"
    """Arrived while the board was stopped (not matched)."""
    UNKNOWN_ID = "unknown_id"
    """Names a stimulus id the board does not know (not matched)."""


def answer_reason(outcome: Outcome) -> protocols.NackReason:
    """The reason of the ACK that answers a DECISION with ``outcome``: NONE when it was
    scored, NOT_RUNNING while stopped, UNKNOWN_STIMULUS for an id not known (SPEC §3.5.2;
    counted all the same)."""
    return {Outcome.WHILE_STOPPED: protocols.NackReason.NOT_RUNNING,
            Outcome.UNKNOWN_ID: protocols.NackReason.UNKNOWN_STIMULUS}.get(
                outcome, protocols.NackReason.NONE)


_KIND_OUTCOME = {MatchKind.DUPLICATE: Outcome.DUPLICATE, MatchKind.LATE: Outcome.LATE,
                 MatchKind.NO_STIMULUS: Outcome.FALSE_ALARM}


MAX_LOGGED_DECISIONS = 100_000
"""Decisions the per-decision log keeps (the first ones; about 20 MB): a decoder under test
that floods the board cannot grow it, or the --score file, without bound. Every decision is
counted all the same."""


class DecisionScoreboard:
    """Accuracy, confusion, latency, misses and every other outcome of a DUT's decisions.

    ``response_window_s`` (s): how long after an onset a decision may arrive and still
    answer it. ``is_known(stimulus_id)`` says whether an id names a stimulus the board
    knows (default: every id). Latencies are board time from the onset to the decision's
    arrival (µs), so they include the decoder's own link. The per-decision log
    (:attr:`log`) holds a few dozen bytes per decision.
    """

    def __init__(self, response_window_s: float,
                 is_known: Callable[[int], bool] | None = None) -> None:
        if not (math.isfinite(response_window_s * 1e6) and response_window_s > 0):
            raise ConfigError(f"response window must be a positive number of seconds, "
                             f"got {response_window_s!r}: give e.g. 1.0")
        self.response_window_s = float(response_window_s)
        self._matcher = OnsetMatcher(int(round(response_window_s * 1e6)))
        self._is_known = is_known or (lambda sid: True)
        self.counts: Counter[Outcome] = Counter()
        self.confusion: Counter[tuple[int, int]] = Counter()
        """(true stimulus id, decided stimulus id) → matched decisions."""
        self.latencies_us: list[int] = []
        """Onset → arrival (µs, board time) of every matched decision."""
        self.hedges = HedgedTrials()
        """The onsets (by time, µs) decided right and those decided more than once."""
        self.log: list[tuple[int, int, float | None, int | None, str, int | None,
                            int | None]] = []
        """Per decision: (arrival µs, stimulus id, confidence, token, outcome, onset µs,
        true id)."""

    def onset(self, stimulus_id: int, t_us: int) -> None:
        """Stimulus ``stimulus_id`` started at board time ``t_us`` (µs), in time order."""
        self._matcher.add_onset(t_us, stimulus_id)

    def decision(self, stimulus_id: int, t_us: int, confidence: float | None = None,
                 running: bool = True, token: int | None = None) -> Outcome:
        """Score a DECISION naming ``stimulus_id`` that arrived at board time ``t_us`` (µs)
        while the board was ``running``; return (and count) its outcome. ``token`` (the
        DECISION's, if any) goes to the log, so a decoder finds its own answers there."""
        onset_us: int | None = None
        true_id: int | None = None
        if not running:
            outcome = Outcome.WHILE_STOPPED
        elif not self._is_known(int(stimulus_id)):
            outcome = Outcome.UNKNOWN_ID
        else:
            m = self._matcher.match(int(t_us))
            if m.onset is not None:
                onset_us, true_id = m.onset.t_us, m.onset.stimulus_id
            if m.kind is MatchKind.MATCHED:
                assert m.onset is not None
                outcome = Outcome.RIGHT if m.onset.stimulus_id == stimulus_id else Outcome.WRONG
                if outcome is Outcome.RIGHT:
                    self.hedges.right.add(m.onset.t_us)
                self.confusion[(m.onset.stimulus_id, int(stimulus_id))] += 1
                self.latencies_us.append(int(t_us) - m.onset.t_us)
            else:
                outcome = _KIND_OUTCOME[m.kind]
                if m.kind is MatchKind.DUPLICATE and m.onset is not None:
                    self.hedges.again.add(m.onset.t_us)
        self.counts[outcome] += 1
        if len(self.log) < MAX_LOGGED_DECISIONS:
            self.log.append((int(t_us), int(stimulus_id), confidence, token, outcome.value,
                             onset_us, true_id))
        return outcome

    def advance(self, t_us: int) -> int:
        """Board time is now ``t_us`` (µs): count the onsets whose response window passed
        without a decision as misses; return how many new ones."""
        return self._matcher.resolve(int(t_us))

    @property
    def decisions(self) -> int:
        """DECISIONs scored (the sum of every outcome)."""
        return sum(self.counts.values())

    @property
    def matched(self) -> int:
        return self.counts[Outcome.RIGHT] + self.counts[Outcome.WRONG]

    @property
    def accuracy(self) -> float:
        """Right / (matched + missed); nan before any onset is scored."""
        scored = self.matched + self._matcher.misses
        return self.counts[Outcome.RIGHT] / scored if scored else math.nan

    def latency_ms(self) -> dict[str, float]:
        """p50 and p99 of the onset → arrival latency (ms, board time); nan when none."""
        if not self.latencies_us:
            return {"p50": math.nan, "p99": math.nan}
        p50, p99 = np.percentile(np.asarray(self.latencies_us) * 1e-3, [50, 99])
        return {"p50": float(p50), "p99": float(p99)}

    def summary(self, with_log: bool = False) -> dict[str, Any]:
        """The scoreboard as a plain dict (JSON-ready; nan as None): the headline ``score``
        (SPEC.md §3.5.4, the contact tasks' rule), counters, accuracy,
        latency (ms), the confusion as ``[true id, decided id, count]`` rows and, with
        ``with_log``, the per-decision log."""
        lat = self.latency_ms()
        charged = self._matcher.onsets + self.decisions - self.matched
        out: dict[str, Any] = {
            "score": headline(self.counts[Outcome.RIGHT], self.hedges, charged),
            "hedged": self.hedges.voided,
            "response_window_s": self.response_window_s,
            "onsets": self._matcher.onsets, "decisions": self.decisions,
            **{o.value: self.counts[o] for o in Outcome},
            "matched": self.matched, "misses": self._matcher.misses,
            "pending": self._matcher.pending,
            "accuracy": None if math.isnan(self.accuracy) else self.accuracy,
            "latency_ms": {k: None if math.isnan(v) else round(v, 3) for k, v in lat.items()},
            "confusion": [[t, d, n] for (t, d), n in sorted(self.confusion.items())],
        }
        if with_log:
            if self.decisions > len(self.log):
                out["log_omitted"] = self.decisions - len(self.log)
            out["log"] = [dict(zip(("t_us", "stimulus_id", "confidence", "token", "outcome",
                                    "onset_us", "true_id"), row, strict=True))
                          for row in self.log]
        return out


def scoreboard_text(summary: dict[str, Any]) -> str:
    """One line of a :meth:`DecisionScoreboard.summary`, for people."""
    if not summary["decisions"]:
        return (f"DUT: no DECISION received for {summary['onsets']} stimuli (a decoder under "
                "test answers with DECISION: protocols/SPEC.md §3.5.1)")
    acc = summary["accuracy"]
    lat = summary["latency_ms"]
    lat_text = ("no latency yet" if lat["p50"] is None
                else f"latency p50 {lat['p50']:.1f} ms p99 {lat['p99']:.1f} ms")
    return (f"DUT: {summary['decisions']} decisions for {summary['onsets']} stimuli: "
            f"{summary['right']} right, {summary['wrong']} wrong, {summary['misses']} missed"
            f" (accuracy {'n/a' if acc is None else f'{100 * acc:.1f} %'}); {lat_text}; "
            f"{summary['late']} late, {summary['duplicates']} duplicates, "
            f"{summary['false_alarms']} false alarms, {summary['while_stopped']} while "
            f"stopped, {summary['unknown_id']} unknown id")
