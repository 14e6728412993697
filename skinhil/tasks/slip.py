"""SLIP: the object slips now (no values): a matched answer is a detection, its latency the
score; an answer matching no slip is a false alarm."""

from __future__ import annotations

from typing import Any

import protocols
from skinhil.tasks.task import TaskDef, TrialKind

SLIP_WINDOW_US = 150_000
"""A SLIP answers a slip only within this long (µs) of its onset (the response window of
the other tasks is a touch's; a slip's onset is the instant the stick ends): the reference
receiver's slip latency on training seeds fits inside it
(``benchmarks/fit_slip_window.py``), and a blind cadence or a delay after each touch lands
in it only by chance."""


def summary(score: Any, board: Any) -> dict[str, Any]:
    """False alarms per minute of board time (None before any time passed)."""
    minutes = board.board_us / 60e6
    return {"false_alarms_per_min": (round(score.counts["false_alarms"] / minutes, 3)
                                     if minutes > 0 else None)}


TASK = TaskDef(layout=protocols.ANSWER_LAYOUTS[protocols.Task.SLIP], trials=TrialKind.SLIP,
               summary=summary, reference="skinhil.receiver.task_decoders:slip_time_us",
               window_us=SLIP_WINDOW_US, detection=True)
