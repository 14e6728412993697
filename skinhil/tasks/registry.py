"""The tasks the board poses and the receiver answers: every ``skinhil.tasks`` entry point
(each a :class:`~skinhil.tasks.task.TaskDef`), plus those :func:`register` adds in process.
A task's answer layout joins :data:`protocols.ANSWER_LAYOUTS` when it is registered."""

from __future__ import annotations

import logging
from collections.abc import Iterable
from importlib.metadata import entry_points

import protocols
from skinhil.errors import ConfigError
from skinhil.tasks.task import TaskDef

log = logging.getLogger(__name__)

GROUP = "skinhil.tasks"
"""The entry-point group of the tasks."""

_TASKS: dict[int, TaskDef] = {}
_loaded = False


def register(task: TaskDef) -> TaskDef:
    """Add ``task`` (and its answer layout); the same task again is a no-op. Raises
    ConfigError when its wire id or name is another task's."""
    if not isinstance(task, TaskDef):
        raise ConfigError(f"{task!r} is no skinhil.tasks.TaskDef: give a task module's TASK")
    for other in _TASKS.values():
        if other is not task and (other.wire_id == task.wire_id or other.name == task.name):
            raise ConfigError(f"task {task.name!r} (id {task.wire_id}) clashes with "
                              f"{other.name!r} (id {other.wire_id}): give it a free id and name")
    try:
        protocols.register_answer_layout(task.layout)
    except protocols.errors.ProtocolError as exc:
        raise ConfigError(str(exc)) from None
    _TASKS[task.wire_id] = task
    return task


def _load() -> None:
    global _loaded
    if _loaded:
        return
    for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name):
        try:
            task = ep.load()
        except (ImportError, AttributeError) as exc:
            raise ConfigError(f"task entry point {ep.name} = {ep.value} does not load "
                              f"({exc}): fix or uninstall the package declaring it") from None
        register(task)
    _loaded = True  # only once every entry point is in: a failed load fails every call


def tasks() -> dict[int, TaskDef]:
    """Every task by wire id, in id order."""
    _load()
    return dict(sorted(_TASKS.items()))


def task(wire_id: int) -> TaskDef | None:
    """The task of ``wire_id``, or None."""
    _load()
    return _TASKS.get(int(wire_id))


def by_name(name: str) -> TaskDef:
    """The task called ``name`` (lower case); raises ConfigError for an unknown name."""
    for t in tasks().values():
        if t.name == name.lower():
            return t
    names = ", ".join(t.name for t in tasks().values())
    raise ConfigError(f"no task {name!r}: give one of {names}")


def tasks_mask(wire_ids: Iterable[int]) -> int:
    """The SESSION's ``tasks`` bitmask (bit ``n`` for task id ``n``) of ``wire_ids``."""
    mask = 0
    for t in wire_ids:
        mask |= 1 << int(t)
    return mask
