"""What a board announces of its run (SPEC.md §3.7), gathered from its session records: the
SESSION (its tasks bitmask, blind link, held object), the SUITE (suite, version, case) and
the TASK records after it (each posed task's tolerance with its unit, its classes)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import protocols
from protocols.answer_layouts import ANSWER_LAYOUTS


@dataclass
class Announcement:
    """The session records of one announcement: the last ``session``, its ``suite`` (None
    until the SUITE arrives: a board of an earlier revision sends none) and ``tasks``, the
    TASK records after the SUITE by task id. :attr:`complete` once the SUITE's ``n_tasks``
    TASK records are in."""

    session: protocols.Session | None = None
    suite: protocols.SuiteEntry | None = None
    tasks: dict[int, protocols.TaskEntry] = field(default_factory=dict)

    def take(self, record: Any) -> bool:
        """Take a session record; True when it completes the announcement (the SUITE and
        all its TASK records are in). A SESSION starts a new announcement."""
        if isinstance(record, protocols.Session):
            self.session, self.suite, self.tasks = record, None, {}
            return False
        if isinstance(record, protocols.SuiteEntry):
            self.suite, self.tasks = record, {}
        elif isinstance(record, protocols.TaskEntry) and self.suite is not None:
            self.tasks[int(record.task)] = record
        else:
            return False
        return self.complete

    @property
    def complete(self) -> bool:
        """The SUITE and every TASK record it announced are in."""
        return self.suite is not None and len(self.tasks) == self.suite.n_tasks

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the suite (``name-vVERSION``, case; None without one), whether an object
        is held, and per posed task (by name) its tolerance, unit and classes."""
        s, suite = self.session, self.suite
        return {
            "suite": None if suite is None or not suite.name else {
                "id": f"{suite.name}-v{suite.version}", "name": suite.name,
                "version": suite.version, "case": suite.case},
            "held_object": None if s is None else bool(s.held_object),
            "blind": None if s is None else bool(s.blind),
            "tasks": {_task_name(t): {"tolerance": e.tolerance, "unit": e.unit,
                                      "classes": list(e.classes)}
                      for t, e in sorted(self.tasks.items())}}


def _task_name(task: int) -> str:
    """The task's name (its answer layout's), or its id for a task this receiver lacks."""
    layout = ANSWER_LAYOUTS.get(task)
    return layout.name if layout is not None else str(task)
