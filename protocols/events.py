"""The address-event record shared by the wire codecs, the model and the receiver (which
import it from here, or through its re-export ``skinhil.events``).

An event is one spike: ``t`` the board time in microseconds (int64, a multiple of the
simulation step), ``addr`` the channel (sensor/spring index 0..337, uint16; also readable as
``x`` for tonic), ``p`` the polarity (always 1 for spikes; kept for tonic compatibility).
"""

from __future__ import annotations

import numpy as np

EVENT_DTYPE = np.dtype([("t", "<i8"), (("x", "addr"), "<u2"), ("p", "i1")])
"""numpy structured dtype of an event array: fields ``t`` (µs), ``addr`` (alias ``x``), ``p``."""


def make_events(t_us: np.ndarray, addr: np.ndarray) -> np.ndarray:
    """Build an event array from spike times (µs) and channel addresses, in the given order."""
    t = np.asarray(t_us, dtype=np.int64)
    a = np.asarray(addr)
    ev = np.empty(t.shape[0], dtype=EVENT_DTYPE)
    ev["t"] = t
    ev["addr"] = a
    ev["p"] = 1
    return ev
