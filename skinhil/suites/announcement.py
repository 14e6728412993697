"""What a board announces of the suite case it plays (SPEC.md §3.7): the SUITE record's
suite, version and case, and a TASK record per posed task (its wire id from the tasks
registry, its tolerance with the unit and its classes from the case). The command line hands
them to the board, which never knows suites."""

from __future__ import annotations

from typing import Any

import protocols
from skinhil.suites.case import Case, PosedTask, Suite
from skinhil.tasks.registry import by_name


def task_entry(posed: PosedTask) -> protocols.TaskEntry:
    """The TASK record of a posed task: its wire id, tolerance (in ``posed.unit``; None:
    none), unit and classes."""
    return protocols.TaskEntry(by_name(posed.name).wire_id, posed.tolerance, posed.unit,
                               tuple(float(c) for c in posed.classes))


def announcement(suite: Suite, case: Case) -> dict[str, Any]:
    """The board's configuration fields (``suite_name``, ``suite_version``, ``suite_case``,
    ``task_terms``: :class:`firmware_sim.config.BoardConfig`) that announce ``case`` of
    ``suite``."""
    return {"suite_name": suite.name, "suite_version": suite.version,
            "suite_case": case.name, "task_terms": tuple(task_entry(t) for t in case.tasks)}
