"""Declarative checks for the parameter dataclasses, after scikit-learn's
``_parameter_constraints``.

A parameter class declares what each field takes, once, as a class attribute; its
``__post_init__`` calls :func:`validate_params` and then checks only the rules that tie
fields together::

    @dataclass(frozen=True)
    class PSPParams:
        tau_d_ms: float = 4.0

        _parameter_constraints: ClassVar[Constraints] = {
            "tau_d_ms": Interval(Real, 0, None, closed="neither", unit="ms"),
        }

        def __post_init__(self) -> None:
            validate_params(self)

A field's entry is one constraint or a list of alternatives (the value passes if any one
accepts it; ``None`` in the list accepts ``None``). The first field whose value no
alternative accepts raises :class:`~skinhil.errors.ConfigError` in one line naming the
parameter, the value given and what to give instead, with its unit::

    SkinParams.mass_kg = -1.0 — give a finite number > 0 (kg)

Intervals refuse NaN, booleans and, unless a bound is ``math.inf`` itself, infinities: an
unbounded side (``None``) means "any finite number", as every parameter here needs.
"""

from __future__ import annotations

import math
import numbers
from abc import ABC, abstractmethod
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Any, Literal, TypeAlias

from skinhil.errors import ConfigError

Closed = Literal["left", "right", "both", "neither"]


class Constraint(ABC):
    """What one parameter accepts; ``hint`` (optional) is said after what to give."""

    hint: str = ""

    @abstractmethod
    def is_satisfied_by(self, value: object) -> bool:
        """Whether ``value`` is allowed."""

    @abstractmethod
    def describe(self) -> str:
        """What is allowed, as the object of "give ...", with its unit."""


class Interval(Constraint):
    """Numbers of ``kind`` (``numbers.Real`` or ``numbers.Integral``) between ``left`` and
    ``right`` (``None``: unbounded, finite), each end included as ``closed`` says; ``unit``
    is the unit the parameter is in (said in the message)."""

    def __init__(self, kind: type, left: float | None, right: float | None, *,
                 closed: Closed, unit: str = "", hint: str = "") -> None:
        if kind not in (numbers.Real, numbers.Integral):
            raise TypeError(f"Interval kind must be numbers.Real or numbers.Integral, "
                            f"not {kind!r}")
        if closed not in ("left", "right", "both", "neither"):
            raise TypeError(f"Interval closed must be left, right, both or neither, "
                            f"not {closed!r}")
        if left is not None and right is not None and left > right:
            raise TypeError(f"Interval left {left!r} is above right {right!r}")
        self.kind = kind
        self.left = left
        self.right = right
        self.closed = closed
        self.unit = unit
        self.hint = hint

    def is_satisfied_by(self, value: object) -> bool:
        if isinstance(value, bool) or not isinstance(value, self.kind):
            return False
        x: Any = value
        try:
            as_float = float(x)
        except OverflowError:  # a whole number beyond a float's range: finite, compared exactly
            as_float = 0.0
        if math.isnan(as_float):
            return False
        if math.isinf(as_float) and as_float not in (self.left, self.right):
            return False
        lo_in = self.closed in ("left", "both")
        hi_in = self.closed in ("right", "both")
        if self.left is not None and (x < self.left or (x == self.left and not lo_in)):
            return False
        return not (self.right is not None and (x > self.right
                                                or (x == self.right and not hi_in)))

    def describe(self) -> str:
        noun = "whole number" if self.kind is numbers.Integral else "finite number"
        lo_in = self.closed in ("left", "both")
        hi_in = self.closed in ("right", "both")
        lo = None if self.left in (None, -math.inf) else self.left
        hi = None if self.right in (None, math.inf) else self.right
        if lo is not None and hi is not None:
            text = (f"a {noun} in {'[' if lo_in else '('}{_number(lo)}, {_number(hi)}"
                    f"{']' if hi_in else ')'}")
        elif lo is not None:
            text = f"a {noun} {'>=' if lo_in else '>'} {_number(lo)}"
        elif hi is not None:
            text = f"a {noun} {'<=' if hi_in else '<'} {_number(hi)}"
        else:
            text = f"a {noun}"
        if self.unit:
            text = f"{text} ({self.unit})"
        extra = [s for s, ok in (("-inf", self.left == -math.inf and lo_in),
                                 ("inf", self.right == math.inf and hi_in)) if ok]
        return f"{text}, or {' or '.join(extra)}" if extra else text


def _number(x: float) -> str:
    return str(x) if isinstance(x, int) else f"{x:g}"


class Options(Constraint):
    """One of a fixed set of values (compared with ``==``), said in the given order."""

    def __init__(self, options: Collection[object], hint: str = "") -> None:
        if not options:
            raise TypeError("Options needs at least one option")
        self.options = tuple(options)
        self.hint = hint

    def is_satisfied_by(self, value: object) -> bool:
        try:
            return any(bool(value == o) and isinstance(value, bool) == isinstance(o, bool)
                       for o in self.options)
        except (TypeError, ValueError):  # an array compared with a value
            return False

    def describe(self) -> str:
        names = [repr(o) for o in self.options]
        if len(names) == 1:
            return names[0]
        return f"{', '.join(names[:-1])} or {names[-1]}"


class StrOptions(Options):
    """One of a set of strings; a set is said sorted, a sequence in its order."""

    def __init__(self, options: Collection[str], hint: str = "") -> None:
        ordered = sorted(options) if isinstance(options, set | frozenset) else list(options)
        super().__init__(ordered, hint)

    def is_satisfied_by(self, value: object) -> bool:
        return isinstance(value, str) and value in self.options


class InstanceOf(Constraint):
    """An instance of ``kind`` (booleans never count as numbers)."""

    def __init__(self, kind: type | tuple[type, ...], what: str = "", hint: str = "") -> None:
        self.kind = kind
        kinds = kind if isinstance(kind, tuple) else (kind,)
        self.what = what or " or ".join(f"a {k.__module__}.{k.__qualname__}"
                                        if k.__module__ not in ("builtins",)
                                        else f"a {k.__qualname__}" for k in kinds)
        self.hint = hint

    def is_satisfied_by(self, value: object) -> bool:
        if isinstance(value, bool) and bool not in (
                self.kind if isinstance(self.kind, tuple) else (self.kind,)):
            return False
        return isinstance(value, self.kind)

    def describe(self) -> str:
        return self.what


class Predicate(Constraint):
    """Whatever ``test`` accepts, described as ``what`` (a rule no other kind states)."""

    def __init__(self, test: Callable[[Any], bool], what: str, hint: str = "") -> None:
        self.test = test
        self.what = what
        self.hint = hint

    def is_satisfied_by(self, value: object) -> bool:
        try:
            return bool(self.test(value))
        except (TypeError, ValueError, ArithmeticError):
            return False

    def describe(self) -> str:
        return self.what


class _NoneConstraint(Constraint):
    def is_satisfied_by(self, value: object) -> bool:
        return value is None

    def describe(self) -> str:
        return "None"


Declaration: TypeAlias = "Constraint | None | Sequence[Constraint | None]"
Constraints: TypeAlias = "Mapping[str, Declaration]"
"""A class's ``_parameter_constraints``: field name → constraint or list of alternatives."""


def _alternatives(declared: Declaration) -> list[Constraint]:
    items = list(declared) if isinstance(declared, Sequence) else [declared]
    return [_NoneConstraint() if c is None else c for c in items]


def refusal(where: str, name: str, value: object, declared: Declaration) -> str:
    """The one-line message for ``value`` of parameter ``name`` refused by ``declared``."""
    options = _alternatives(declared)
    allowed = " or ".join(c.describe() for c in options)
    hints = "; ".join(dict.fromkeys(c.hint for c in options if c.hint))
    shown = repr(value)
    if len(shown) > 60:
        shown = shown[:57] + "..."
    return f"{where}{name} = {shown} — give {allowed}" + (f"; {hints}" if hints else "")


def check_param(name: str, value: object, declared: Declaration, where: str = "") -> None:
    """:class:`ConfigError` unless one of the alternatives ``declared`` accepts ``value``;
    ``where`` (e.g. ``"SkinParams."``) prefixes the parameter's name in the message."""
    if not any(c.is_satisfied_by(value) for c in _alternatives(declared)):
        raise ConfigError(refusal(where, name, value, declared))


def validate_params(obj: object, where: str | None = None) -> None:
    """Check every field ``type(obj)._parameter_constraints`` declares, in declaration
    order; the first refused raises :class:`ConfigError` (module docstring). ``where``
    names the object in the message (default: its class, as ``"SkinParams."``; give e.g.
    ``"stimulus 'A': "`` for a named instance)."""
    constraints: Constraints = type(obj)._parameter_constraints  # type: ignore[attr-defined]
    prefix = f"{type(obj).__name__}." if where is None else where
    for name, declared in constraints.items():
        check_param(name, getattr(obj, name), declared, prefix)


def positive(unit: str, hint: str = "") -> Interval:
    """A finite number > 0 in ``unit``: the most common declaration."""
    return Interval(numbers.Real, 0, None, closed="neither", unit=unit, hint=hint)


def non_negative(unit: str, hint: str = "") -> Interval:
    """A finite number >= 0 in ``unit``."""
    return Interval(numbers.Real, 0, None, closed="left", unit=unit, hint=hint)


def finite(unit: str = "", hint: str = "") -> Interval:
    """Any finite number, in ``unit``."""
    return Interval(numbers.Real, None, None, closed="neither", unit=unit, hint=hint)


PROBABILITY = Interval(numbers.Real, 0, 1, closed="both", unit="probability")
"""A probability, 0..1 inclusive."""


__all__ = ["PROBABILITY", "Closed", "Constraint", "Constraints", "Declaration", "InstanceOf",
           "Interval", "Options", "Predicate", "StrOptions", "check_param", "finite",
           "non_negative", "positive", "refusal", "validate_params"]
