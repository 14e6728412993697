"""Pacing to the wire budget: never faster than the real link, even on a pty or vcan.

A pty ignores the baud rate and a vcan has no bit timing, so the board keeps the link's
clock itself. :class:`WirePacer` tracks when the emulated wire becomes free: sending a
payload that lasts ``d`` seconds on the wire (``Transport.wire_seconds``: 10 bits per byte for
8N1 serial, worst-case stuffed bits for CAN) moves that time ``d`` later. A byte or frame may
start only while the wire is free within ``allowance_s`` (a transmit buffer of that many
seconds), so over any interval of length ``T`` at most ``T + allowance_s`` seconds of wire
time and one byte or frame more are handed to the OS: bytes/s ≤ baud/10 and CAN frames at
the bitrate.
"""

from __future__ import annotations

import time


class WirePacer:
    """Wire-time bookkeeping on ``time.monotonic``; ``allowance_s`` is the transmit buffer (s)."""

    def __init__(self, allowance_s: float) -> None:
        self.allowance_s = float(allowance_s)
        self.free_at = 0.0
        """Monotonic time (s) at which the emulated wire has sent everything handed to it."""
        self.busy_s = 0.0
        """Total wire time (s) used."""

    def room_s(self, now: float | None = None) -> float:
        """Wire time (s) that may be handed to the OS now."""
        now = time.monotonic() if now is None else now
        return max(0.0, now + self.allowance_s - max(self.free_at, now))

    def used(self, wire_s: float, now: float | None = None) -> None:
        """Account ``wire_s`` seconds of payload handed to the OS at ``now``."""
        now = time.monotonic() if now is None else now
        self.free_at = max(self.free_at, now) + wire_s
        self.busy_s += wire_s

    def idle_at(self) -> float:
        """Monotonic time (s) at which everything handed over has left the emulated wire."""
        return self.free_at
