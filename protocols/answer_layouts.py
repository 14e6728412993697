"""The layout of each task's values in an ANSWER's 28-bit field (SPEC.md §3.5.3).

The ANSWER record stays generic on the wire (a task id and its values); this table says, per
task id, how many values it carries, their names (with units), their wire step and their
bit width. The codecs and :func:`protocols.dbc.dbc_text` read it; a task defined outside
this package adds its layout at run time with :func:`register_answer_layout`.
"""

from __future__ import annotations

import dataclasses

from protocols.errors import ProtocolError

ANSWER_FIELD_BITS = 28
"""An ANSWER's argument: bits 3..0 the task, bits 31..4 its 28-bit field (SPEC.md §3.5.3)."""
MAX_TASK_ID = 15
"""Task ids are 4 bits on the wire."""


@dataclasses.dataclass(frozen=True)
class AnswerLayout:
    """How one task's values fill an ANSWER's 28-bit field.

    ``fields`` the names of the values in order, each ending in its unit (``x_mm``,
    ``force_n``); value ``i`` takes ``bits`` bits from bit ``i * bits`` of the field, as a
    count of ``scale`` (one wire step, in the value's unit), two's complement when
    ``signed``. An ``integer`` value travels as itself (scale 1) and decodes as an int.
    ``units`` the unit of each value as a DBC shows it (``"mm"``; ``""``: none) and
    ``signals`` its DBC signal name (``"AnswerXmm"``).
    """

    task: int
    name: str
    fields: tuple[str, ...]
    bits: int = ANSWER_FIELD_BITS
    scale: float = 1.0
    signed: bool = False
    integer: bool = False
    units: tuple[str, ...] = ()
    signals: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not 0 <= int(self.task) <= MAX_TASK_ID:
            raise ProtocolError(f"answer layout {self.name!r}: task id {self.task} is outside "
                                f"0..{MAX_TASK_ID}; give a free 4-bit id")
        if len(self.fields) * self.bits > ANSWER_FIELD_BITS:
            raise ProtocolError(f"answer layout {self.name!r}: {len(self.fields)} values of "
                                f"{self.bits} bits exceed the {ANSWER_FIELD_BITS}-bit field; "
                                "give fewer or narrower values")
        for what in (self.units, self.signals):
            if what and len(what) != len(self.fields):
                raise ProtocolError(f"answer layout {self.name!r}: give one unit and one "
                                    f"signal name per value ({len(self.fields)})")

    def signal_names(self) -> tuple[str, ...]:
        """The DBC signal name of each value (``Answer`` and its field in CamelCase unless
        :attr:`signals` names them)."""
        return self.signals or tuple(
            "Answer" + "".join(p.capitalize() for p in f.split("_")) for f in self.fields)

    def unit_names(self) -> tuple[str, ...]:
        """The DBC unit of each value (:attr:`units`, or none)."""
        return self.units or ("",) * len(self.fields)

    @property
    def steps(self) -> tuple[int, int]:
        """The least and greatest count each value can carry."""
        if self.signed:
            return -(1 << (self.bits - 1)), (1 << (self.bits - 1)) - 1
        return 0, (1 << self.bits) - 1

    @property
    def value_range(self) -> tuple[float, float]:
        """The least and greatest value (in the fields' unit) each value can carry."""
        lo, hi = self.steps
        return lo * self.scale, hi * self.scale


BUILT_IN_LAYOUTS = (
    AnswerLayout(0, "classification", ("stimulus_id",), bits=24, integer=True),
    AnswerLayout(1, "localisation", ("x_mm", "y_mm"), bits=14, scale=0.01, signed=True,
                 units=("mm", "mm"), signals=("AnswerXmm", "AnswerYmm")),
    AnswerLayout(2, "force", ("force_n",), scale=1e-6, units=("N",),
                 signals=("AnswerForceN",)),
    AnswerLayout(3, "slip", ()),
    AnswerLayout(4, "vibration", ("frequency_hz",), scale=1e-3, units=("Hz",),
                 signals=("AnswerFrequencyHz",)),
)
"""The tasks SPEC.md §3.5.3 defines: 1 id, 0.01 mm, 1 µN, none, 1 mHz per step."""

ANSWER_LAYOUTS: dict[int, AnswerLayout] = {lay.task: lay for lay in BUILT_IN_LAYOUTS}
"""Task id → its layout: the built-in ones and those registered at run time."""


def register_answer_layout(layout: AnswerLayout) -> AnswerLayout:
    """Add ``layout`` to :data:`ANSWER_LAYOUTS` (the same layout again is a no-op); raises
    ProtocolError when its task id is taken by another layout."""
    have = ANSWER_LAYOUTS.get(int(layout.task))
    if have is not None and have != layout:
        raise ProtocolError(f"task id {layout.task} already has the answer layout "
                            f"{have.name!r}; give {layout.name!r} a free id")
    ANSWER_LAYOUTS[int(layout.task)] = layout
    return layout


def answer_layout(task: int) -> AnswerLayout | None:
    """The layout of ``task``, or None for a task id no layout defines."""
    return ANSWER_LAYOUTS.get(int(task))
