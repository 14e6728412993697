"""Scoring decisions against the ground truth: one matching rule
(:mod:`skinhil.scoring.matching`) for the board's scoreboard of a decoder under test
(:mod:`skinhil.scoring.scoreboard`) and the reference receiver's own scoring; the ANSWERs of
the contact tasks against the world's truth (:mod:`skinhil.scoring.tasks`)."""

from skinhil.scoring.matching import Match, MatchKind, Onset, OnsetMatcher
from skinhil.scoring.scoreboard import (
    DecisionScoreboard,
    Outcome,
    answer_reason,
    scoreboard_text,
)
from skinhil.scoring.tasks import TaskScoreboard, truth_lines

__all__ = ["DecisionScoreboard", "Match", "MatchKind", "Onset", "OnsetMatcher", "Outcome",
           "TaskScoreboard", "answer_reason", "scoreboard_text", "truth_lines"]
