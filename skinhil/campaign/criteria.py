"""Pass criteria: a number of the board's score file, addressed by a dotted path, compared
with a threshold (``accuracy >= 0.8``, ``latency_ms.p99 <= 250``,
``tasks.localisation.median_error_mm <= 3``).

A criterion reads whatever keys the score file has (``serve --score FILE``, JSON): the path's
parts are object keys, or list indices for lists. A value of ``null`` there (the board had
nothing to measure it on, e.g. no decision at all) fails the criterion; a path the score file
does not hold is not the decoder's failure but a campaign the rig cannot judge
(:class:`MissingKey`).
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from skinhil.errors import ConfigError

OPERATORS: dict[str, Callable[[float, float], bool]] = {
    ">=": operator.ge, "<=": operator.le, ">": operator.gt, "<": operator.lt,
    "==": operator.eq, "!=": operator.ne}
"""The comparisons a criterion may make."""

_SYNTAX = re.compile(r"^\s*([A-Za-z_][\w-]*(?:\.[\w-]+)*)\s*(>=|<=|==|!=|>|<)\s*(\S+)\s*$")


class MissingKey(LookupError):
    """The score file holds no value at a criterion's path."""


@dataclass(frozen=True)
class Criterion:
    """``path op threshold``: the score file's number at ``path`` compared with
    ``threshold`` (in the unit of that number)."""

    path: str
    op: str
    threshold: float

    def __str__(self) -> str:
        return f"{self.path} {self.op} {self.threshold:g}"

    def value(self, score: Mapping[str, Any]) -> float | None:
        """The number at :attr:`path` of ``score`` (None: ``null`` there), or
        :class:`MissingKey` when there is none, or it is not a number."""
        node: Any = score
        for part in self.path.split("."):
            if isinstance(node, Mapping) and part in node:
                node = node[part]
            elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
                node = node[int(part)]
            else:
                raise MissingKey(f"the score file has no '{self.path}' ('{part}' not found)")
        if node is None:
            return None
        if isinstance(node, bool) or not isinstance(node, int | float):
            raise MissingKey(f"the score file's '{self.path}' is not a number but "
                             f"{type(node).__name__}")
        return float(node)

    @property
    def upper_bound(self) -> bool:
        """Whether the criterion only bounds its value from above (``<=``, ``<``): a score
        with no answer at all meets it."""
        return self.op in ("<=", "<")

    def holds(self, value: float | None) -> bool:
        """Whether ``value`` (from :meth:`value`) meets the criterion; None never does."""
        return value is not None and not math.isnan(value) and \
            OPERATORS[self.op](value, self.threshold)


def answers(score: Mapping[str, Any]) -> int:
    """The decoder's answers the score file counts: its DECISIONs (``decisions``), its
    ANSWERs of every task (``tasks.<task>.answers``) and its GRIPs, accepted or refused
    (``grasp.grips``)."""
    n = int(score.get("decisions") or 0)
    for task in (score.get("tasks") or {}).values():
        if isinstance(task, Mapping):
            n += int(task.get("answers") or 0)
    grips = (score.get("grasp") or {}).get("grips") or {}
    if isinstance(grips, Mapping):
        n += sum(int(v) for v in grips.values() if isinstance(v, int))
    return n


def parse_criterion(text: object, where: str) -> Criterion:
    """The criterion written as ``text`` (``"accuracy >= 0.8"``), else a one-line
    :class:`ConfigError` naming ``where``."""
    match = _SYNTAX.match(text) if isinstance(text, str) else None
    if match is None:
        raise ConfigError(f"{where}: criterion {text!r} — write \"PATH OP NUMBER\", e.g. "
                          f"\"accuracy >= 0.8\" (OP one of {' '.join(OPERATORS)})")
    path, op, number = match.groups()
    try:
        threshold = float(number)
    except ValueError:
        raise ConfigError(f"{where}: criterion {text!r}: {number!r} is not a number — give "
                          "the threshold as a number, e.g. 0.8 or 250") from None
    if math.isnan(threshold):
        raise ConfigError(f"{where}: criterion {text!r}: the threshold is nan — give a number")
    return Criterion(path, op, threshold)
