"""Serial framing primitives (compiled): CRC-16/CCITT-FALSE and COBS.

A packet on the wire is ``COBS(body + CRC16(body) big-endian) + 0x00`` (SPEC.md §2); the
CRC over a body followed by its CRC is zero, which is how a decoder checks it.
"""

from __future__ import annotations

import numba
import numpy as np


def _crc_table() -> np.ndarray:
    table = np.zeros(256, dtype=np.uint16)
    for i in range(256):
        c = i << 8
        for _ in range(8):
            c = ((c << 1) ^ 0x1021) if c & 0x8000 else (c << 1)
        table[i] = c & 0xFFFF
    return table


CRC_TABLE = _crc_table()
"""CRC-16/CCITT-FALSE table (polynomial 0x1021, MSB first)."""

CRC_INIT = 0xFFFF
"""CRC-16/CCITT-FALSE initial value (no final XOR, no reflection)."""


@numba.njit(cache=True, nogil=True)
def crc16(buf: np.ndarray, start: int, stop: int) -> int:
    """CRC-16/CCITT-FALSE of ``buf[start:stop]`` (uint8 array)."""
    crc = CRC_INIT
    for i in range(start, stop):
        crc = ((crc << 8) & 0xFFFF) ^ CRC_TABLE[((crc >> 8) ^ buf[i]) & 0xFF]
    return crc


@numba.njit(cache=True, nogil=True)
def frame_into(body: np.ndarray, n: int, out: np.ndarray, pos: int) -> int:
    """Append ``COBS(body[:n] + crc16) + 0x00`` to ``out`` at ``pos``; return the new end.

    ``body`` must have room for two more bytes after ``n`` (the CRC is written there).
    ``out`` needs ``n + 2 + (n + 2) // 254 + 2`` free bytes.
    """
    crc = crc16(body, 0, n)
    body[n] = crc >> 8
    body[n + 1] = crc & 0xFF
    m = n + 2
    code_pos = pos
    pos += 1
    code = 1
    for i in range(m):
        b = body[i]
        if b == 0:
            out[code_pos] = code
            code_pos = pos
            pos += 1
            code = 1
        else:
            out[pos] = b
            pos += 1
            code += 1
            if code == 255:
                out[code_pos] = code
                code_pos = pos
                pos += 1
                code = 1
    out[code_pos] = code
    out[pos] = 0
    return pos + 1


@numba.njit(cache=True, nogil=True)
def cobs_decode(buf: np.ndarray, start: int, stop: int, out: np.ndarray) -> int:
    """COBS-decode ``buf[start:stop]`` (no zero inside) into ``out``; length, or -1 if invalid."""
    i = start
    n = 0
    while i < stop:
        code = buf[i]
        if code == 0 or i + code > stop:
            return -1
        for j in range(i + 1, i + code):
            out[n] = buf[j]
            n += 1
        i += code
        if code < 255 and i < stop:
            out[n] = 0
            n += 1
    return n


@numba.njit(cache=True, nogil=True)
def chain_starts(buf: np.ndarray, start: int, stop: int, valid: np.ndarray) -> None:
    """``valid[k - start]`` = True where a COBS block chain starting at ``k`` ends at ``stop``."""
    for k in range(stop - 1, start - 1, -1):
        code = buf[k]
        nxt = k + code
        valid[k - start] = code != 0 and (nxt == stop or (nxt < stop and valid[nxt - start]))
