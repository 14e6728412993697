"""Numbers fixed by the protocol specification (SPEC.md)."""

from __future__ import annotations

PROTOCOL_VERSION = 1
"""Version carried by SYNC packets/frames and status flags."""

N_CHANNELS = 338
"""Event addresses are 0..N_CHANNELS-1 (one per spring sensor)."""

DEFAULT_STEP_US = 100
"""Default time step of event stamps (µs); the stream carries the actual value in SYNC."""

DEFAULT_FLUSH_US = 1000
"""Default longest time one events packet/frame spans (µs): frames leave at least every ms."""

DEFAULT_SYNC_US = 50_000
"""Default longest time between two SYNCs while events flow (µs)."""

BITMAP_BYTES = 43
"""Bytes of a per-step channel bitmap (338 bits, LSB first, 6 zero padding bits)."""
