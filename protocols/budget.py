"""Wire time of serial bytes and CAN frames, so an emulator can pace a pty or vcan to the real link.

Serial is 8N1 (10 bits per byte). CAN frames use the 11-bit (base) format and the worst-case
bit stuffing (one stuff bit after every four bits of the stuffed fields), which is what a
real bus must be able to carry; CAN FD frames switch to ``data_bitrate`` for the data phase
(bit-rate switch) when it is given.
"""

from __future__ import annotations

from protocols.errors import ProtocolError
from protocols.records import CanFrame

SERIAL_BITS_PER_BYTE = 10
"""8N1: start bit, 8 data bits, stop bit."""

CAN_FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
"""The data lengths a CAN FD frame can have (index = DLC code)."""


def serial_seconds(n_bytes: int, baud: int) -> float:
    """Seconds a UART at ``baud`` (bits/s, 8N1) needs to send ``n_bytes`` bytes."""
    if baud <= 0:
        raise ProtocolError(f"baud rate must be positive, got {baud}; pass e.g. 921600")
    return n_bytes * SERIAL_BITS_PER_BYTE / baud


def can_frame_bits(frame: CanFrame) -> tuple[int, int]:
    """Worst-case bits of ``frame``: (bits at the nominal rate, bits at the data rate).

    Classic frames have every bit at the nominal rate (second value 0). CAN FD frames count
    the arbitration phase (SOF..BRS, CRC delimiter, ACK, EOF, intermission) at the nominal
    rate and the data phase (ESI, DLC, data, stuff count, CRC with its fixed stuff bits) at
    the data rate.
    """
    n = len(frame.data)
    if frame.is_fd:
        if n not in CAN_FD_LENGTHS:
            raise ProtocolError(f"CAN FD frame of {n} bytes: use one of {CAN_FD_LENGTHS}")
        arb = 17 + (17 - 1) // 4 + 1 + 2 + 7 + 3  # SOF..BRS stuffed, CRC delim, ACK, EOF, IFS
        crc = 17 if n <= 16 else 21
        dyn = 5 + 8 * n  # ESI, DLC, data: dynamic stuffing
        data = dyn + (dyn - 1) // 4 + 4 + crc + (4 + crc + 3) // 4 + 1
        return arb, data
    if n > 8:
        raise ProtocolError(f"classic CAN frame of {n} bytes: at most 8; use CAN FD for more")
    stuffed = 34 + 8 * n  # SOF, ID, RTR, IDE, r0, DLC, data, CRC
    return stuffed + (stuffed - 1) // 4 + 1 + 2 + 7 + 3, 0


def can_frame_seconds(frame: CanFrame, bitrate: int, data_bitrate: int | None = None) -> float:
    """Worst-case seconds ``frame`` occupies a bus at ``bitrate`` (and ``data_bitrate`` for FD).

    Without ``data_bitrate`` an FD frame is sent without bit-rate switch (all at ``bitrate``).
    """
    if bitrate <= 0 or (data_bitrate is not None and data_bitrate <= 0):
        raise ProtocolError(f"CAN bitrates must be positive, got {bitrate}/{data_bitrate}")
    nominal, data = can_frame_bits(frame)
    return nominal / bitrate + data / (data_bitrate or bitrate)
