"""The board's scoring of ANSWERs (``protocols/SPEC.md`` §3.5.3, §3.5.4): localisation,
force, slip and vibration, against the world's ground truth of every tick.

Trials come from the truth (:mod:`skinhil.world.truth`), one row per contact per tick:

- a **touch** of a contact starts at the first tick it touches (``nodes`` > 0) after at least
  :data:`TOUCH_GAP_US` without touching; LOCALISATION and FORCE answer touches, VIBRATION
  the touches of contacts that vibrate;
- a **slip** of a contact starts at the first tick of gross slip (``slip`` = gross) once its
  touch has lasted :data:`SETTLE_US` (the touch-down, where nodes slide as they land, is no
  slip) and at least :data:`SLIP_GAP_US` after its last gross slip; SLIP answers slips.

An answer is matched to the latest trial onset of its task by the one rule of
:mod:`skinhil.scoring.matching` (response window ``W``). A matched answer is scored against
the trial's truth at the answer's tick (the last tick of the trial once it has ended):

- LOCALISATION: error = distance (mm) from the contact's centroid; right when at most
  ``tolerance_mm``;
- FORCE: error = |answer − normal force| (N); right when at most ``tolerance_n``;
- VIBRATION: the class is the frequency played in the scene nearest the answer; right when
  it is the trial's (the error in Hz is kept too);
- SLIP: a matched answer is a detection (``right``), its latency the score; its window is
  :data:`skinhil.tasks.slip.SLIP_WINDOW_US` from the slip's onset (the task's
  ``window_us``), so an answer during the stick (before the slip) or past that window is a
  false alarm (or late).

Every answer lands in exactly one counter: right, wrong, duplicates, late, false_alarms,
while_stopped; every trial is matched, missed or pending.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Collection
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from skinhil.scoring.headline import HedgedTrials, detection_headline, headline
from skinhil.scoring.matching import MatchKind, OnsetMatcher
from skinhil.tasks import TaskDef, TrialKind, registry
from skinhil.world.truth import SLIP_STATES, T_NODES, T_NORMAL, T_SLIP, T_X, T_Y

TOUCH_GAP_US = 20_000
"""A contact's touch ends only after this long (µs) without touching: a vibration's brief
lift-offs stay one touch."""
SLIP_GAP_US = 200_000
"""A slip ends only after this long (µs) without gross slip: stick-slip chatter, and the
unloading slip as a sliding object is lifted, belong to the slip before."""
SAMPLE_US = 50_000
"""The truth file's values of a touch are those this long (µs) after its onset."""
SETTLE_US = 20_000
"""Gross slip in a touch's first this long (µs) is its touch-down, no slip."""
GROSS = SLIP_STATES.index("gross")
DEFAULT_TOLERANCE_MM = 0.5
"""A localisation answer within this distance (mm) of the centroid is right: half a spacing
of the paper's skin (neighbouring nodes told apart)."""
DEFAULT_TOLERANCE_N = 0.05
"""A force answer within this (N) of the normal force is right."""

MAX_VERDICTS = 100_000
"""Verdicts kept per task for the score file (about 15 MB of JSON); past them an answer is
still counted, and ``verdicts_not_kept`` says how many were not written."""

OUTCOMES = ("right", "wrong", "duplicates", "late", "false_alarms", "while_stopped")
"""The counters every answer of a task lands in, one each."""


@dataclass
class Trial:
    """One trial of a task: contact ``contact`` from ``t0_us``; its truth now (or at its
    last tick): centroid (mm), normal force (N), frequency (Hz)."""

    t0_us: int
    contact: int
    x_mm: float = math.nan
    y_mm: float = math.nan
    normal_n: float = math.nan
    frequency_hz: float = 0.0
    last_us: int = 0
    sample: tuple[float, float, float] | None = None
    """(x_mm, y_mm, normal_n) at :data:`SAMPLE_US` after the onset: the settled touch the
    operator's truth file gives."""


@dataclass
class TaskScore:
    """One task's counters, errors and latencies."""

    task: TaskDef
    matcher: OnsetMatcher
    trials: list[Trial] = field(default_factory=list)
    counts: Counter[str] = field(default_factory=Counter)
    errors: list[float] = field(default_factory=list)
    """Per matched answer: the error (mm, N or Hz; none for SLIP)."""
    latencies_us: list[int] = field(default_factory=list)
    """Per matched answer: onset → arrival (µs, board time)."""
    verdicts: list[dict[str, Any]] = field(default_factory=list)
    """Per answer, the first :data:`MAX_VERDICTS`: what it said, the trial it answered and
    its outcome (:meth:`TaskScoreboard.answer`)."""
    hedges: HedgedTrials = field(default_factory=HedgedTrials)
    """The trials answered right and those answered more than once (:func:`headline`)."""

    def add_trial(self, trial: Trial) -> None:
        self.matcher.add_onset(trial.t0_us, len(self.trials))
        self.trials.append(trial)


class TaskScoreboard:
    """Scores ANSWERs of LOCALISATION, FORCE, SLIP and VIBRATION against the truth.

    ``frequencies_hz[c]`` is contact ``c``'s vibration frequency (0: none);
    ``response_window_s`` as the DECISION scoreboard's; ``only``: pose just the tasks it
    names (a suite case poses those whose value varies in it), else every task the trials
    allow. Call :meth:`observe` once per tick
    with the tick's truth rows, :meth:`answer` for each ANSWER, :meth:`advance` as board
    time moves on.
    """

    def __init__(self, frequencies_hz: list[float], response_window_s: float,
                 tolerance_mm: float = DEFAULT_TOLERANCE_MM,
                 tolerance_n: float = DEFAULT_TOLERANCE_N,
                 only: Collection[str] | None = None) -> None:
        self.frequencies_hz = [float(f) for f in frequencies_hz]
        self.classes_hz = sorted({f for f in self.frequencies_hz if f > 0})
        self.tolerance_mm = float(tolerance_mm)
        self.tolerance_n = float(tolerance_n)
        window_us = int(round(response_window_s * 1e6))
        kinds = {TrialKind.TOUCH, TrialKind.SLIP}
        if self.classes_hz:
            kinds.add(TrialKind.VIBRATING_TOUCH)
        self.tasks = {wire_id: TaskScore(t, OnsetMatcher(
                          window_us if t.window_us is None else min(window_us, t.window_us)))
                      for wire_id, t in registry.tasks().items()
                      if t.trials in kinds and (only is None or t.name in only)}
        """Per posed task id (id order): its score."""
        n = len(self.frequencies_hz)
        self._touch_last = np.full(n, -10**12, dtype=np.int64)
        self._slip_last = np.full(n, -10**12, dtype=np.int64)
        self._touch_t0 = np.zeros(n, dtype=np.int64)
        self._touch_trial: list[list[Trial]] = [[] for _ in range(n)]
        """Per contact: its open touch trials (one per touch task)."""
        self._slip_trial: list[Trial | None] = [None] * n
        self.board_us = 0
        self.not_posed: Counter[int] = Counter()

    def posed(self, task: int) -> bool:
        """Whether ``task`` is scored here."""
        return task in self.tasks

    def observe(self, t_us: int, raw: np.ndarray) -> None:
        """The truth of the tick at board time ``t_us`` (µs): the kernel's rows
        (n_contacts, RAW_FIELDS), SI units."""
        touching = raw[:, T_NODES] > 0
        gross = raw[:, T_SLIP] == GROSS
        for c in np.flatnonzero(touching).tolist():
            row = raw[c]
            if t_us - self._touch_last[c] > TOUCH_GAP_US:
                self._touch_trial[c] = self._new_touch(t_us, c)
                self._touch_t0[c] = t_us
            for trial in self._touch_trial[c]:
                trial.x_mm, trial.y_mm = row[T_X] * 1e3, row[T_Y] * 1e3
                trial.normal_n = float(row[T_NORMAL])
                trial.last_us = t_us
                if trial.sample is None and t_us - trial.t0_us >= SAMPLE_US:
                    trial.sample = (trial.x_mm, trial.y_mm, trial.normal_n)
            self._touch_last[c] = t_us
            if gross[c] and t_us - self._touch_t0[c] >= SETTLE_US:
                if t_us - self._slip_last[c] > SLIP_GAP_US:
                    for score in self.tasks.values():
                        if score.task.trials is TrialKind.SLIP:
                            score.add_trial(Trial(t_us, c))
                self._slip_last[c] = t_us

    def _new_touch(self, t_us: int, c: int) -> list[Trial]:
        out = []
        touch = {TrialKind.TOUCH}
        if self.frequencies_hz[c] > 0:
            touch.add(TrialKind.VIBRATING_TOUCH)
        for score in self.tasks.values():
            if score.task.trials in touch:
                trial = Trial(t_us, c, frequency_hz=self.frequencies_hz[c])
                score.add_trial(trial)
                out.append(trial)
        return out

    def answer(self, answer: Any, t_us: int, running: bool = True) -> str:
        """Score ``answer`` (:class:`protocols.Answer` of a posed task) arriving at board
        time ``t_us`` (µs); return (and count) its outcome, one of :data:`OUTCOMES`."""
        score = self.tasks[int(answer.task)]  # type: ignore[index]
        trial_index: int | None = None
        error: float | None = None
        if not running:
            outcome = "while_stopped"
        else:
            m = score.matcher.match(int(t_us))
            if m.onset is not None:
                trial_index = m.onset.stimulus_id
            if m.kind is MatchKind.MATCHED:
                assert trial_index is not None
                trial = score.trials[trial_index]
                score.latencies_us.append(int(t_us) - trial.t0_us)
                outcome, error = self._verdict(score, trial, answer.values)
                if outcome == "right":
                    score.hedges.right.add(trial_index)
            else:
                if m.kind is MatchKind.DUPLICATE and trial_index is not None:
                    score.hedges.again.add(trial_index)
                outcome = {MatchKind.DUPLICATE: "duplicates", MatchKind.LATE: "late",
                           MatchKind.NO_STIMULUS: "false_alarms"}[m.kind]
        score.counts[outcome] += 1
        if len(score.verdicts) < MAX_VERDICTS:
            score.verdicts.append({
                "t_us": int(t_us), "token": int(answer.token),
                "values": [round(float(v), 6) for v in answer.values],
                "trial": trial_index,
                "trial_t_us": None if trial_index is None else score.trials[trial_index].t0_us,
                "outcome": outcome, "error": None if error is None else round(error, 6)})
        return outcome

    def _verdict(self, score: TaskScore, trial: Trial,
                 values: tuple[float, ...]) -> tuple[str, float | None]:
        verdict = score.task.judge(trial, tuple(values), self)
        if verdict.error is not None:
            score.errors.append(verdict.error)
        return ("right" if verdict.right else "wrong"), verdict.error

    def advance(self, t_us: int) -> None:
        """Board time is now ``t_us`` (µs): trials whose window passed become misses."""
        self.board_us = int(t_us)
        for score in self.tasks.values():
            score.matcher.resolve(int(t_us))

    def summary(self, with_verdicts: bool = False) -> dict[str, dict[str, Any]]:
        """Per task name: the headline ``score``, counters, accuracy, error and latency
        percentiles (JSON-ready); with ``with_verdicts``, every answer's verdict too.

        ``score`` charges every answer (SPEC.md §3.5.4, :func:`headline`; a detection
        task's, SLIP's, by :func:`detection_headline`); None before the first trial or answer."""
        out: dict[str, dict[str, Any]] = {}
        for s in self.tasks.values():
            matched = s.counts["right"] + s.counts["wrong"]
            scored = matched + s.matcher.misses
            answers = sum(s.counts.values())
            charged = s.matcher.onsets + answers - matched
            d: dict[str, Any] = {
                "score": (detection_headline(s.counts["right"], s.hedges, s.matcher.onsets,
                                             answers - matched)
                          if s.task.detection else headline(s.counts["right"], s.hedges, charged)),
                "trials": s.matcher.onsets, "answers": answers,
                **{o: s.counts[o] for o in OUTCOMES},
                "matched": matched, "misses": s.matcher.misses, "pending": s.matcher.pending,
                "hedged": s.hedges.voided,
                "accuracy": s.counts["right"] / scored if scored else None,
                "latency_ms": _percentiles([v * 1e-3 for v in s.latencies_us]),
            }
            unit = s.task.error_unit
            if unit is not None:
                err = _percentiles(s.errors)
                d[f"median_error_{unit}"] = err["p50"]
                d[f"p90_error_{unit}"] = err["p90"]
            d.update(s.task.summary(s, self))
            if with_verdicts:
                d["verdicts"] = s.verdicts
                d["verdicts_not_kept"] = answers - len(s.verdicts)
            out[s.task.name] = d
        for code, n in sorted(self.not_posed.items()):
            known = registry.task(code)
            name = known.name if known is not None else f"task_{code}"
            out.setdefault(name, {})["not_posed"] = n
        return out


def _percentiles(values: list[float]) -> dict[str, float | None]:
    if not values:
        return {"p50": None, "p90": None}
    p50, p90 = np.percentile(np.asarray(values, dtype=float), [50, 90])
    return {"p50": round(float(p50), 4), "p90": round(float(p90), 4)}


def truth_lines(board_tasks: TaskScoreboard) -> list[str]:
    """One JSON line per trial of each task: its task, onset (µs), contact and truth (a
    touch's centroid and normal force :data:`SAMPLE_US` after its onset, or at its end)."""
    out = []
    for score in board_tasks.tasks.values():
        for t in score.trials:
            x, y, n = t.sample if t.sample is not None else (t.x_mm, t.y_mm, t.normal_n)
            out.append(json.dumps({
                "type": "trial", "task": score.task.name, "t_us": t.t0_us,
                "contact": t.contact, "x_mm": _num(x), "y_mm": _num(y),
                "normal_n": _num(n), "frequency_hz": t.frequency_hz}))
    return out


def _num(v: float) -> float | None:
    return None if math.isnan(v) else round(float(v), 6)
