"""Numbers fixed by the protocol specification (SPEC.md)."""

from __future__ import annotations

PROTOCOL_VERSION = 3
"""Version of the narrow format (9-bit addresses), carried by SYNC packets/frames and status
flags of a stream whose channels all fit it. Versions 1 and 2 (retired) framed serial packets
with a CRC blind to appended zeros (SPEC.md §2); no decoder reads them."""

WIDE_VERSION = 4
"""Version of the wide format (20-bit addresses, SPEC.md §9), for skins of more channels."""

KNOWN_VERSIONS = (PROTOCOL_VERSION, WIDE_VERSION)
"""Versions the decoders read."""

N_CHANNELS = 338
"""Narrow event addresses are 0..N_CHANNELS-1 (the paper's 6x6 skin: one per spring sensor)."""

WIDE_ADDR_BITS = 20
"""Address bits of a wide event word (the other 4 of its 24 bits are the step delta)."""

WIDE_MAX_CHANNELS = (1 << WIDE_ADDR_BITS) - 1
"""Wide addresses are 0..WIDE_MAX_CHANNELS-1 on the wire (the all-ones address is invalid)."""

DEFAULT_STEP_US = 100
"""Default time step of event stamps (µs); the stream carries the actual value in SYNC."""

DEFAULT_SYNC_US = 50_000
"""Default longest time between two SYNCs while events flow (µs)."""

BITMAP_BYTES = 43
"""Bytes of a per-step channel bitmap (338 bits, LSB first, 6 zero padding bits)."""

MAX_CAN_CLASS = 12
"""Highest CAN frame class a board sends or reads (ID = class << 4 | board id, SPEC.md §5.1):
1..7 the stream, 8..12 the session records; 13..15 are reserved for future records."""
