"""A board's score at the end of a run: its DECISION scoreboard, its task scoreboard and its
held object's scores, as ``serve --score`` writes them and ``skinhil.Board.score`` returns
them (:func:`skinhil.scoring.score_file.score_record`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from skinhil.plant.report import plant_scores
from skinhil.scoring.score_file import score_record

if TYPE_CHECKING:
    from firmware_sim.board import Board


def grasp_scores(board: Board) -> dict[str, Any]:
    """``{"grasp": ...}``, the held object's scores, or {} for a board that holds none."""
    if board.plant is None:
        return {}
    return {"grasp": plant_scores(board.plant, board.truth)}


def board_score(board: Board) -> dict[str, Any]:
    """The score file's content for ``board`` (JSON-ready)."""
    tasks = board.tasks.summary(with_verdicts=True) if board.tasks is not None else {}
    return score_record(board.scoreboard, tasks, grasp_scores(board))
