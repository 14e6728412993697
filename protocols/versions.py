"""Which protocol version a stream uses, and a decoder's refusal of versions it does not read.

Version 1 (narrow: 9-bit addresses, SPEC.md §3-§5) carries the paper's 6x6 skin and any
board of at most 338 channels byte for byte as before; version 4 (wide: 20-bit addresses,
SPEC.md §9) carries larger skins. The SYNC announces the version (serial byte 2, CAN FD
byte 1 bits 7..4, classic CAN byte 0 bit 7).
"""

from __future__ import annotations

import numpy as np

from protocols.constants import (
    KNOWN_VERSIONS,
    N_CHANNELS,
    PROTOCOL_VERSION,
    WIDE_MAX_CHANNELS,
    WIDE_VERSION,
)
from protocols.errors import ProtocolError
from protocols.events import EVENT_DTYPE

MAX_CHANNELS = min(WIDE_MAX_CHANNELS, int(np.iinfo(EVENT_DTYPE["addr"]).max) + 1)
"""Most channels a stream has here: the wide format's address range, capped by the event
array's address field (uint16: 65,536 channels, up to a 63x63 skin)."""


def wire_version(n_channels: int) -> int:
    """The version a board of ``n_channels`` channels sends: narrow (3) when its addresses
    fit 0..337, else wide (4). Raises ProtocolError outside 1..MAX_CHANNELS."""
    if not 1 <= int(n_channels) <= MAX_CHANNELS:
        raise ProtocolError(f"{n_channels} channels: a stream carries 1..{MAX_CHANNELS}; "
                            "use a smaller skin or split it over several boards")
    return PROTOCOL_VERSION if int(n_channels) <= N_CHANNELS else WIDE_VERSION


def check_versions(versions: tuple[int, ...]) -> tuple[int, ...]:
    """``versions`` as a sorted tuple if every one is known and there is one, else
    ProtocolError."""
    vs = tuple(sorted({int(v) for v in versions}))
    if not vs or any(v not in KNOWN_VERSIONS for v in vs):
        raise ProtocolError(f"decoder versions {versions!r}: choose among {KNOWN_VERSIONS}")
    return vs


def refuse_version(seen_mask: int, versions: tuple[int, ...]) -> None:
    """Raise ProtocolError if the stream announced (bit v of ``seen_mask``: a SYNC of
    version v) a version outside ``versions``."""
    for v in KNOWN_VERSIONS:
        if seen_mask >> v & 1 and v not in versions:
            what = "wide addresses: more than 338 channels" if v == WIDE_VERSION else \
                "narrow addresses: at most 338 channels"
            raise ProtocolError(
                f"the stream is protocol version {v} ({what}); this decoder reads version "
                f"{', '.join(map(str, versions))}: decode it with a decoder of version {v} "
                f"(the default reads {', '.join(map(str, KNOWN_VERSIONS))})")
