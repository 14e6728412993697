"""The tasks: one module per task, each exposing ``TASK`` (a :class:`TaskDef`), found through
the ``skinhil.tasks`` entry points by :mod:`skinhil.tasks.registry`."""

from skinhil.tasks.registry import by_name, register, task, tasks, tasks_mask
from skinhil.tasks.task import Judging, TaskDef, TrialKind, TrialTruth, Verdict

__all__ = ["Judging", "TaskDef", "TrialKind", "TrialTruth", "Verdict", "by_name", "register",
           "task", "tasks", "tasks_mask"]
