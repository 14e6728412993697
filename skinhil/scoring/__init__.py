"""Scoring decisions against the ground truth: one matching rule
(:mod:`skinhil.scoring.matching`) for the board's scoreboard of a decoder under test
(:mod:`skinhil.scoring.scoreboard`) and the reference receiver's own scoring."""

from skinhil.scoring.matching import Match, MatchKind, Onset, OnsetMatcher
from skinhil.scoring.scoreboard import (
    DecisionScoreboard,
    Outcome,
    answer_reason,
    scoreboard_text,
)

__all__ = ["DecisionScoreboard", "Match", "MatchKind", "Onset", "OnsetMatcher", "Outcome",
           "answer_reason", "scoreboard_text"]
