"""The address-event record: defined once in :mod:`protocols.events` (the wire codecs stand
alone), re-exported here for the model and the receiver."""

from __future__ import annotations

from protocols.events import EVENT_DTYPE, make_events

__all__ = ["EVENT_DTYPE", "make_events"]
