"""A board's score at the end of a run: its DECISION scoreboard, its task scoreboard and its
held object's scores, as ``serve --score`` writes them and ``skinhil.Board.score`` returns
them (:func:`skinhil.scoring.score_file.score_record`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import protocols
from skinhil.plant.report import plant_scores
from skinhil.scoring.score_file import score_record

if TYPE_CHECKING:
    from firmware_sim.board import Board


def grasp_scores(board: Board) -> dict[str, Any]:
    """``{"grasp": ...}``, the held object's scores, or {} for a board that holds none.
    Its ``"grips"`` count every GRIP the board received once: ``accepted`` (ACKed),
    ``refused_*`` by the held object (NACKed with the reason), and ``refused_busy``: refused
    for want of room in the command queue before reaching the object (NACKed BUSY while the
    answer budget lasts, else unanswered; :mod:`firmware_sim.command_budget`). A GRIP still
    waiting in the queue when the run ended is in none of them (never executed, never
    answered)."""
    if board.plant is None:
        return {}
    scores = plant_scores(board.plant, board.truth)
    busy = board.counters.busy_by_opcode.get(int(protocols.CommandCode.GRIP), 0)
    scores["grips"] = {**scores["grips"], "refused_busy": busy}
    return {"grasp": scores}


def board_score(board: Board) -> dict[str, Any]:
    """The score file's content for ``board`` (JSON-ready)."""
    tasks = board.tasks.summary(with_verdicts=True) if board.tasks is not None else {}
    return score_record(board.scoreboard, tasks, grasp_scores(board))
