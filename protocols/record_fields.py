"""Field conversions shared by the serial and CAN record layouts."""

from __future__ import annotations

import enum
import math
import struct
from typing import TypeVar

from protocols.errors import ProtocolError
from protocols.records import (
    CONFIDENCE_STEPS,
    Command,
    CommandCode,
    Decision,
)

E = TypeVar("E", bound=enum.IntEnum)


def check_uint(value: int, bits: int, what: str) -> int:
    """Return ``value`` if it fits an unsigned ``bits``-bit field, else raise ProtocolError."""
    v = int(value)
    if not 0 <= v < (1 << bits):
        raise ProtocolError(f"{what} {value} does not fit {bits} unsigned bits "
                            f"(0..{(1 << bits) - 1})")
    return v


def arg_bits(opcode: int, arg: int | float) -> int:
    """The 32-bit wire form of a command argument: binary32 for SET_SNR, else uint32."""
    if int(opcode) == CommandCode.SET_SNR:
        a = float(arg)
        if math.isnan(a):
            raise ProtocolError("SET_SNR argument is NaN; give a level in dB or inf")
        return int.from_bytes(struct.pack("<f", a), "little")
    if isinstance(arg, float) and not arg.is_integer():
        raise ProtocolError(f"command argument {arg} must be an integer for opcode {opcode}")
    return check_uint(int(arg), 32, "command argument")


def arg_value(opcode: int, bits: int) -> int | float:
    """The argument a 32-bit wire field carries (float for SET_SNR, int otherwise)."""
    if opcode == CommandCode.SET_SNR:
        return float(struct.unpack("<f", bits.to_bytes(4, "little"))[0])
    return bits


def command_fields(command: Command | Decision) -> tuple[int, int, int]:
    """(token, opcode, 32-bit argument) of a COMMAND unit; a :class:`Decision` packs its
    stimulus id in bits 23..0 and its confidence in bits 31..24 (SPEC.md §3.5)."""
    token = check_uint(command.token, 16, "token")
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
    opcode = check_uint(int(command.opcode), 8, "opcode")
    return token, opcode, arg_bits(opcode, command.arg)


def command_record(token: int, opcode: int, bits: int) -> Command | Decision:
    """The record a COMMAND unit carries: a :class:`Decision` for opcode ``DECISION``
    (a confidence byte 255 means none; 255 is the only value above 254), else a
    :class:`Command`."""
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
