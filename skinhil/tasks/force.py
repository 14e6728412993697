"""FORCE: how hard a touch presses (values ``(force_n,)``, the normal force, N); right
within the scoreboard's ``tolerance_n`` of the contact's normal force."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import protocols
from skinhil.tasks.task import Judging, TaskDef, TrialKind, TrialTruth, Verdict


def rule(trial: TrialTruth, values: tuple[float, ...], judging: Judging) -> Verdict:
    """Error: |answer − normal force| (N)."""
    err = abs(values[0] - trial.normal_n)
    return Verdict(err <= judging.tolerance_n, err)


def oracle_values(truth: Mapping[str, Any]) -> tuple[float, ...]:
    """The trial's normal force (N)."""
    return (round(float(truth["normal_n"]), 2),)


TASK = TaskDef(layout=protocols.ANSWER_LAYOUTS[protocols.Task.FORCE], trials=TrialKind.TOUCH,
               truth=("normal_n",), rule=rule, error_unit="n", oracle_values=oracle_values,
               reference="skinhil.receiver.task_decoders:force_n")
