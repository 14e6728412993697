"""Serial framing primitives (compiled): CRC-16/GENIBUS and COBS.

A packet on the wire is ``COBS(body + CRC16(body) big-endian) + 0x00`` (SPEC.md §2). The CRC
ends with a final XOR (0xFFFF), so the register over a body followed by its CRC is the fixed
residue 0x1D0F, which is how a decoder checks it. Zero bytes appended to a packet (what
``0x01`` bytes inserted before its delimiter decode to) move that register away from the
residue for any count below 32,767: unlike a CRC without final XOR, whose residue 0 stays 0
under appended zeros, this one never passes them.
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
"""CRC-16 table (polynomial 0x1021, MSB first)."""

CRC_INIT = 0xFFFF
"""CRC-16/GENIBUS initial value (no reflection)."""

CRC_XOROUT = 0xFFFF
"""CRC-16/GENIBUS final XOR: the sent CRC is the register XOR this."""

CRC_RESIDUE = 0x1D0F
"""The register (:func:`crc16`) over a body followed by its sent CRC: a packet checks iff its
decoded bytes give this value."""


@numba.njit(cache=True, nogil=True)
def crc16(buf: np.ndarray, start: int, stop: int) -> int:
    """CRC register (polynomial 0x1021, initial 0xFFFF, before the final XOR) over
    ``buf[start:stop]`` (uint8 array); the sent CRC-16/GENIBUS is this XOR :data:`CRC_XOROUT`."""
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
    crc = crc16(body, 0, n) ^ CRC_XOROUT
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


MAX_SHIFT_BYTES = 2048
"""Longest zero-byte shift :data:`X8N` tabulates (more than any candidate, 1032 bytes)."""


def _x8n_table() -> np.ndarray:
    table = np.zeros(MAX_SHIFT_BYTES + 1, dtype=np.int64)
    r = 1
    for n in range(MAX_SHIFT_BYTES + 1):
        table[n] = r
        r = ((r << 8) & 0xFFFF) ^ int(CRC_TABLE[(r >> 8) & 0xFF])
    return table


X8N = _x8n_table()
"""``X8N[n]`` = x^(8n) modulo the CRC polynomial: the register after ``n`` zero bytes fed
from register 1. The register after ``Y`` fed from ``s`` is ``s · X8N[len(Y)] ^ crc0(Y)``
(``crc0``: from register 0), which lets a decoder check every suffix of a candidate at once."""


@numba.njit(cache=True, nogil=True)
def gf_mulmod(a: int, b: int) -> int:
    """``a · b`` modulo the CRC polynomial 0x11021 (16-bit registers as GF(2) polynomials)."""
    r = 0
    for i in range(15, -1, -1):
        r = ((r << 1) ^ (0x1021 if r & 0x8000 else 0)) & 0xFFFF
        if (b >> i) & 1:
            r ^= a
    return r


@numba.njit(cache=True, nogil=True)
def suffix_checks(buf: np.ndarray, first: int, stop: int, prefix: np.ndarray,
                  length: np.ndarray, reg: np.ndarray, passes: np.ndarray) -> None:
    """Mark every start ``k`` in ``[first, stop)`` whose suffix ``buf[k:stop]`` is a COBS
    block chain ending at ``stop`` that decodes to at least 4 bytes passing the CRC:
    ``passes[k - first]``. Linear in ``stop - first`` (at most :data:`MAX_SHIFT_BYTES`):
    prefix registers of the raw bytes give each block's register in O(1), and each suffix's
    register follows from the next block's by one shift (``X8N``). Scratch arrays
    ``prefix``, ``length``, ``reg`` hold ``stop - first + 1`` values."""
    w = stop - first
    r = 0
    prefix[0] = 0
    for i in range(w):
        r = ((r << 8) & 0xFFFF) ^ CRC_TABLE[((r >> 8) ^ buf[first + i]) & 0xFF]
        prefix[i + 1] = r
    for k in range(stop - 1, first - 1, -1):
        j = k - first
        code = int(buf[k])
        nxt = k + code
        length[j] = -1
        passes[j] = False
        if code == 0 or nxt > stop or (nxt < stop and length[nxt - first] < 0):
            continue
        hl = code - 1  # the block's data bytes buf[k+1 : nxt], register from 0
        head = prefix[nxt - first] ^ gf_mulmod(prefix[j + 1], X8N[hl])
        if nxt == stop:
            n = hl
            rr = head
        else:
            sep = 1 if code < 255 else 0  # the zero the block stands for
            tail = length[nxt - first]
            n = hl + sep + tail
            rr = gf_mulmod(head, X8N[sep + tail]) ^ reg[nxt - first]
        length[j] = n
        reg[j] = rr
        passes[j] = n >= 4 and (gf_mulmod(CRC_INIT, X8N[n]) ^ rr) == CRC_RESIDUE
