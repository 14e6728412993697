"""Reading and rewriting the board's sequence number of one serial packet or CAN frame.

A sender that inserts a record of its own into a recorded stream (a replay answering a host
command, SPEC.md "Capture files") gives it the next sequence number and adds one to the
number of every later board packet or frame, so a decoder sees an unbroken count (SPEC.md
§6 rule 4). Pure: bytes and :class:`protocols.CanFrame` in, the same out.
"""

from __future__ import annotations

import numpy as np

from protocols import serial_kernels as k
from protocols.framing import cobs_decode, frame_into
from protocols.records import CanFrame

SERIAL_SEQ_MOD = 256
"""Serial and CAN FD sequence numbers count modulo 256; classic CAN modulo 16."""
CLASSIC_SEQ_MOD = 16


def _body(packet: bytes) -> np.ndarray | None:
    """The body of ``packet`` without its CRC, or None if it does not COBS-decode to 4 to
    ``MAX_BODY + 2`` bytes (a longer run is no packet, SPEC.md §6 rule 3)."""
    raw = np.frombuffer(packet.rstrip(b"\0"), dtype=np.uint8)
    if raw.shape[0] > k.MAX_WIRE:
        return None
    out = np.empty(raw.shape[0] + 8, dtype=np.uint8)  # COBS decodes to fewer bytes
    n = cobs_decode(raw, 0, raw.shape[0], out)
    return None if n < 4 or n - 2 > k.MAX_BODY else out[:n - 2]


def serial_packet_seq(packet: bytes) -> int | None:
    """The sequence number (body byte 1) of one COBS-framed packet (its delimiter may
    follow), or None if it is not a decodable packet."""
    body = _body(packet)
    return None if body is None else int(body[1])


def serial_packet_with_seq(packet: bytes, seq: int) -> bytes:
    """``packet`` (COBS-framed, delimiter included) with sequence number ``seq`` modulo 256:
    the CRC and the framing recomputed. A packet that does not decode is returned as it is."""
    body = _body(packet)
    if body is None:
        return packet
    buf = np.empty(body.shape[0] + 2, dtype=np.uint8)
    buf[:body.shape[0]] = body
    buf[1] = seq % SERIAL_SEQ_MOD
    m = body.shape[0] + 2
    out = np.empty(m + m // 254 + 2, dtype=np.uint8)  # what frame_into needs at most
    n = frame_into(buf, body.shape[0], out, 0)
    return out[:n].tobytes()


def can_seq_mod(frame: CanFrame) -> int:
    """How many sequence numbers ``frame``'s layout counts: 256 (FD) or 16 (classic)."""
    return SERIAL_SEQ_MOD if frame.is_fd else CLASSIC_SEQ_MOD


def can_frame_seq(frame: CanFrame) -> int:
    """The sequence number of a board frame (byte 0: all of it on FD, bits 3..0 classic);
    0 for a frame without data (no board frame: :func:`can_frame_with_seq` leaves it)."""
    return frame.data[0] % can_seq_mod(frame) if frame.data else 0


def can_frame_with_seq(frame: CanFrame, seq: int) -> CanFrame:
    """``frame`` with sequence number ``seq`` (modulo 256 FD, 16 classic); its other bits
    unchanged. A frame without data (no board frame) is returned as it is."""
    if not frame.data:
        return frame
    mod = can_seq_mod(frame)
    first = (frame.data[0] - frame.data[0] % mod) | (seq % mod)
    return CanFrame(frame.arbitration_id, bytes([first]) + frame.data[1:], frame.is_fd)
