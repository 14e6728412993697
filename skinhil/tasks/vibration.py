"""VIBRATION: what vibrates (values ``(frequency_hz,)``, Hz): the class is the frequency
played in the scene nearest the answer; right when it is the trial's (the error in Hz is
kept too). Posed only when a contact vibrates."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import protocols
from skinhil.tasks.task import Judging, TaskDef, TrialKind, TrialTruth, Verdict


def rule(trial: TrialTruth, values: tuple[float, ...], judging: Judging) -> Verdict:
    """Error: |answer − the trial's frequency| (Hz); right when the nearest class is it."""
    nearest = min(judging.classes_hz, key=lambda f: abs(f - values[0]))
    return Verdict(nearest == trial.frequency_hz, abs(values[0] - trial.frequency_hz))


def oracle_values(truth: Mapping[str, Any]) -> tuple[float, ...]:
    """The trial's frequency (Hz)."""
    return (round(float(truth["frequency_hz"]), 2),)


def summary(score: Any, board: Any) -> dict[str, Any]:
    """The frequencies (Hz) played in the scene."""
    return {"classes_hz": board.classes_hz}


TASK = TaskDef(layout=protocols.ANSWER_LAYOUTS[protocols.Task.VIBRATION],
               trials=TrialKind.VIBRATING_TOUCH, truth=("frequency_hz",), rule=rule,
               error_unit="hz", oracle_values=oracle_values, summary=summary,
               reference="skinhil.receiver.task_decoders:frequency_hz")
