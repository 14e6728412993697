"""CLASSIFICATION: which stimulus (values ``(stimulus_id,)``). It is answered by DECISIONs
and scored by :class:`skinhil.scoring.DecisionScoreboard`: it poses no contact trial."""

from __future__ import annotations

import protocols
from skinhil.tasks.task import TaskDef, TrialKind

TASK = TaskDef(layout=protocols.ANSWER_LAYOUTS[protocols.Task.CLASSIFICATION],
               trials=TrialKind.NONE)
