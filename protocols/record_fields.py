"""Field conversions shared by the serial and CAN record layouts."""

from __future__ import annotations

import enum
import math
import struct
from typing import TypeVar

from protocols.answer_layouts import (
    ANSWER_LAYOUTS,
    AnswerLayout,
    answer_layout,
)
from protocols.errors import ProtocolError
from protocols.records import (
    CONFIDENCE_STEPS,
    Answer,
    Command,
    CommandCode,
    Decision,
    Task,
)

E = TypeVar("E", bound=enum.IntEnum)


def check_uint(value: int, bits: int, what: str) -> int:
    """Return ``value`` if it fits an unsigned ``bits``-bit field, else raise ProtocolError."""
    v = int(value)
    if not 0 <= v < (1 << bits):
        raise ProtocolError(f"{what} {value} does not fit {bits} unsigned bits "
                            f"(0..{(1 << bits) - 1})")
    return v


FLOAT_OPCODES = (CommandCode.SET_SNR, CommandCode.GRIP)
"""Opcodes whose argument is an IEEE-754 binary32 (dB, N)."""


def arg_bits(opcode: int, arg: int | float) -> int:
    """The 32-bit wire form of a command argument: binary32 for SET_SNR and GRIP, else
    uint32."""
    if int(opcode) in FLOAT_OPCODES:
        a = float(arg)
        if math.isnan(a):
            raise ProtocolError(f"{CommandCode(int(opcode)).name} argument is NaN; give a "
                                "number")
        return int.from_bytes(struct.pack("<f", a), "little")
    if isinstance(arg, float) and not arg.is_integer():
        raise ProtocolError(f"command argument {arg} must be an integer for opcode {opcode}")
    return check_uint(int(arg), 32, "command argument")


def arg_value(opcode: int, bits: int) -> int | float:
    """The argument a 32-bit wire field carries (float for SET_SNR and GRIP, int
    otherwise)."""
    if opcode in FLOAT_OPCODES:
        return float(struct.unpack("<f", bits.to_bytes(4, "little"))[0])
    return bits


PLACE_BITS = ANSWER_LAYOUTS[Task.LOCALISATION].bits
"""Each coordinate of a LOCALISATION answer: a signed 14-bit count of 0.01 mm (±81.91 mm)."""


def _layout(task: int) -> AnswerLayout:
    """The layout of ``task``: its registered one, or one raw 28-bit value for an id none
    defines (decoded to be NACKed)."""
    lay = answer_layout(task)
    if lay is None:
        return AnswerLayout(int(task), f"task {int(task)}", ("field",), integer=True)
    return lay


def answer_range(task: int) -> tuple[float, float]:
    """The least and greatest value (units of the task's :class:`AnswerLayout` fields) each
    value of ``task`` can carry on the wire (SPEC.md §3.5.3)."""
    lay = answer_layout(task)
    if lay is None:
        raise ProtocolError(f"task {task} has no answer layout: register one "
                            "(protocols.register_answer_layout)")
    return lay.value_range


def _steps(value: float, lay: AnswerLayout, what: str) -> int:
    """``value`` in wire steps of ``lay``, checked to fit, masked to its bits."""
    if lay.integer:
        return check_uint(int(value), lay.bits, f"ANSWER {what}")
    v = float(value)
    lo, hi = lay.steps
    n = round(v / lay.scale) if math.isfinite(v) else lo - 1
    if not lo <= n <= hi:
        raise ProtocolError(f"ANSWER {what} {value!r} is outside "
                            f"{lo * lay.scale:g}..{hi * lay.scale:g}")
    return n & ((1 << lay.bits) - 1)


def answer_field(answer: Answer) -> int:
    """The 32-bit argument of an :class:`Answer` (SPEC.md §3.5.3): task in bits 3..0, its
    values in bits 31..4 as its :class:`AnswerLayout` says; raises ProtocolError for values
    that do not fit or a wrong count."""
    task = check_uint(int(answer.task), 4, "ANSWER task")
    vals = tuple(answer.values)
    lay = _layout(task)
    if len(vals) != len(lay.fields):
        raise ProtocolError(f"an ANSWER of task {task} carries {len(lay.fields)} value(s), "
                            f"got {len(vals)}: {vals!r}")
    field = 0
    for i, (v, name) in enumerate(zip(vals, lay.fields, strict=True)):
        field |= _steps(v, lay, name) << (i * lay.bits)
    return task | field << 4


def answer_record(token: int, bits: int) -> Answer:
    """The :class:`Answer` a 32-bit ANSWER argument carries (the inverse of
    :func:`answer_field`; reserved bits ignored)."""
    task, field = bits & 0xF, bits >> 4
    lay = _layout(task)
    mask = (1 << lay.bits) - 1
    values: list[float] = []
    for i in range(len(lay.fields)):
        n = (field >> (i * lay.bits)) & mask
        if lay.signed:
            half = 1 << (lay.bits - 1)
            n = (n ^ half) - half
        values.append(n if lay.integer else n * lay.scale)
    return Answer(token, enum_or_int(Task, task), tuple(values))


def command_fields(command: Command | Decision | Answer) -> tuple[int, int, int]:
    """(token, opcode, 32-bit argument) of a COMMAND unit; a :class:`Decision` packs its
    stimulus id in bits 23..0 and its confidence in bits 31..24 (SPEC.md §3.5), an
    :class:`Answer` its task and values (§3.5.3)."""
    token = check_uint(command.token, 16, "token")
    if isinstance(command, Answer):
        return token, int(CommandCode.ANSWER), answer_field(command)
    if isinstance(command, Decision):
        sid = check_uint(command.stimulus_id, 24, "DECISION stimulus_id")
        if command.confidence is None:
            conf = CONFIDENCE_STEPS + 1
        else:
            c = float(command.confidence)
            if not 0.0 <= c <= 1.0:
                raise ProtocolError(f"DECISION confidence {command.confidence!r} is outside "
                                    "0..1: give a value in 0..1, or None")
            conf = round(c * CONFIDENCE_STEPS)
        return token, int(CommandCode.DECISION), sid | conf << 24
    if int(command.opcode) == CommandCode.DECISION:
        raise ProtocolError("a DECISION is sent as a protocols.Decision record, not a Command")
    if int(command.opcode) == CommandCode.ANSWER:
        raise ProtocolError("an ANSWER is sent as a protocols.Answer record, not a Command")
    opcode = check_uint(int(command.opcode), 8, "opcode")
    return token, opcode, arg_bits(opcode, command.arg)


def command_record(token: int, opcode: int, bits: int) -> Command | Decision | Answer:
    """The record a COMMAND unit carries: a :class:`Decision` for opcode ``DECISION``
    (a confidence byte 255 means none; 255 is the only value above 254), an
    :class:`Answer` for ``ANSWER``, else a :class:`Command`."""
    if opcode == CommandCode.ANSWER:
        return answer_record(token, bits)
    if opcode == CommandCode.DECISION:
        conf = bits >> 24
        return Decision(token, bits & 0xFFFFFF,
                        None if conf > CONFIDENCE_STEPS else conf / CONFIDENCE_STEPS)
    return Command(token, enum_or_int(CommandCode, opcode), arg_value(opcode, bits))


def enum_or_int(kind: type[E], value: int) -> E | int:
    """``kind(value)`` if it is a member, else the plain int (unknown codes pass through)."""
    if value in kind._value2member_map_:
        return kind(value)
    return value
