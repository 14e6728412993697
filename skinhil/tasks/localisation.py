"""LOCALISATION: where a touch is (values ``(x_mm, y_mm)``, skin coordinates, mm); right
within the scoreboard's ``tolerance_mm`` of the contact's centroid."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import protocols
from skinhil.tasks.task import Judging, TaskDef, TrialKind, TrialTruth, Verdict


def rule(trial: TrialTruth, values: tuple[float, ...], judging: Judging) -> Verdict:
    """Error: the distance (mm) from the centroid."""
    err = math.hypot(values[0] - trial.x_mm, values[1] - trial.y_mm)
    return Verdict(err <= judging.tolerance_mm, err)


def oracle_values(truth: Mapping[str, Any]) -> tuple[float, ...]:
    """The trial's centroid (mm)."""
    return (round(float(truth["x_mm"]), 2), round(float(truth["y_mm"]), 2))


TASK = TaskDef(layout=protocols.ANSWER_LAYOUTS[protocols.Task.LOCALISATION],
               trials=TrialKind.TOUCH, truth=("x_mm", "y_mm"), rule=rule, error_unit="mm",
               oracle_values=oracle_values,
               reference="skinhil.receiver.task_decoders:touch_spikes")
