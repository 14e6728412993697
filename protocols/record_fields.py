"""Field conversions shared by the serial and CAN record layouts."""

from __future__ import annotations

import enum
import math
import struct
from typing import TypeVar

from protocols.errors import ProtocolError
from protocols.records import CommandCode

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


def enum_or_int(kind: type[E], value: int) -> E | int:
    """``kind(value)`` if it is a member, else the plain int (unknown codes pass through)."""
    if value in kind._value2member_map_:
        return kind(value)
    return value
