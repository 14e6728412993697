"""The score a board writes at the end of a run (``serve --score``, ``skinhil.Board.score``):
one JSON-ready dict, so the command line and the notebook API hand out the same thing."""

from __future__ import annotations

from typing import Any

from skinhil.scoring.scoreboard import DecisionScoreboard


def score_record(scoreboard: DecisionScoreboard, tasks: dict[str, Any] | None = None,
                 extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """``scoreboard``'s summary with every decision, the ANSWERs' scores per task under
    ``"tasks"`` (each answer's verdict with them) and the keys of ``extra`` (``"grasp"``)."""
    return {**scoreboard.summary(with_log=True), "tasks": tasks or {}, **(extra or {})}
