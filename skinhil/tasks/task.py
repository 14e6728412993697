"""What one task is (:class:`TaskDef`): its wire layout, the trials it poses, the truth and
rule it is judged by, its oracle answer and the receiver decoder of its reference answer.
One module per task in this room exposes one as ``TASK``; :mod:`skinhil.tasks.registry`
collects them."""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import protocols


class TrialKind(enum.Enum):
    """Which trials the board poses for a task (:mod:`skinhil.scoring.tasks`)."""

    NONE = "none"
    """No trial of the contact scoreboard (CLASSIFICATION is answered by DECISIONs)."""
    TOUCH = "touch"
    """Every touch of a contact."""
    VIBRATING_TOUCH = "vibrating_touch"
    """Every touch of a contact that vibrates; posed only when a contact vibrates."""
    SLIP = "slip"
    """Every gross slip of a settled touch."""


class TrialTruth(Protocol):
    """The truth of one trial a rule judges: the contact's centroid (mm), normal force (N)
    and vibration frequency (Hz, 0: none) at the answer's tick."""

    x_mm: float
    y_mm: float
    normal_n: float
    frequency_hz: float


class Judging(Protocol):
    """What the scoreboard tells a rule: its tolerances (mm, N) and the frequencies (Hz)
    played in the scene."""

    tolerance_mm: float
    tolerance_n: float
    classes_hz: list[float]


@dataclass(frozen=True)
class Verdict:
    """A matched answer judged: ``right`` or not, and its error (in the task's
    :attr:`TaskDef.error_unit`; None when the task keeps none)."""

    right: bool
    error: float | None = None


Rule = Callable[[TrialTruth, tuple[float, ...], Judging], Verdict]
"""A task's scoring rule: a matched answer's values against its trial's truth."""


@dataclass(frozen=True)
class TaskDef:
    """One task.

    ``layout`` its wire id, name, answer fields (with units), wire scale and range
    (:class:`protocols.AnswerLayout`); ``trials`` which trials it poses; ``truth`` the names
    of the trial's truth (:class:`TrialTruth` attributes, and the truth file's keys) its
    answers are judged against; ``rule`` its scoring rule; ``error_unit`` the suffix of its
    error keys in the score file (``mm``: ``median_error_mm``; None: no error);
    ``oracle_values(truth)`` the true answer from a
    truth-file trial line (a dict); ``reference`` the receiver's decoder of its reference
    answer (``module:function``, read by the reference answerer; empty: none);
    ``summary(score, judging)`` extra keys of its score-file entry; ``window_us`` how long
    (µs) after a trial's onset an answer may match it (None: the board's response window;
    the shorter of the two applies); ``detection``: its answers carry no value to be wrong,
    so its headline charges every answer that matches no trial against a detection
    (:func:`skinhil.scoring.headline.detection_headline`).
    """

    layout: protocols.AnswerLayout
    trials: TrialKind
    truth: tuple[str, ...] = ()
    rule: Rule | None = None
    error_unit: str | None = None
    oracle_values: Callable[[Mapping[str, Any]], tuple[float, ...]] = lambda truth: ()
    reference: str = ""
    summary: Callable[[Any, Any], dict[str, Any]] = field(
        default=lambda score, judging: {})
    window_us: int | None = None
    detection: bool = False

    @property
    def wire_id(self) -> int:
        """The task id an ANSWER carries (4 bits)."""
        return int(self.layout.task)

    @property
    def name(self) -> str:
        """The task's name in the score file and on the command line (lower case)."""
        return self.layout.name

    def judge(self, trial: TrialTruth, values: tuple[float, ...],
              judging: Judging) -> Verdict:
        """The verdict of a matched answer: every answer of a task without a rule is right
        (its arrival is what is scored)."""
        if self.rule is None:
            return Verdict(True)
        return self.rule(trial, values, judging)
