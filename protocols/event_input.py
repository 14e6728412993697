"""Checks and conversion of event arrays handed to an encoder (shared by serial and CAN)."""

from __future__ import annotations

import numpy as np

from protocols.constants import N_CHANNELS
from skinhil.errors import ProtocolError


def check_step_us(step_us: int) -> int:
    """Return ``step_us`` if it is a valid time step (1..65535 µs), else raise ProtocolError."""
    if not 1 <= int(step_us) <= 0xFFFF:
        raise ProtocolError(f"time step {step_us} µs is outside 1..65535 µs; use e.g. 100")
    return int(step_us)


def event_steps(events: np.ndarray, step_us: int, t_end_us: int,
                t_min_us: int) -> tuple[np.ndarray, np.ndarray]:
    """Return (time in steps int64, address uint16) of ``events``, sorted by (time, address).

    Raises ProtocolError if an address is outside 0..337, a time is not a multiple of
    ``step_us``, is before ``t_min_us`` (the end of the previous call) or not before
    ``t_end_us``.
    """
    if events.dtype.names is None or "t" not in events.dtype.names:
        raise ProtocolError("events must be an EVENT_DTYPE array (fields t, addr); "
                            "build it with skinhil.events.make_events")
    n = events.shape[0]
    if n == 0:
        return np.empty(0, np.int64), np.empty(0, np.uint16)
    t = np.asarray(events["t"], dtype=np.int64)
    a = np.asarray(events["addr"])
    if int(a.max()) >= N_CHANNELS or int(a.min()) < 0:
        raise ProtocolError(f"event address outside 0..{N_CHANNELS - 1}: "
                            f"{int(a.min())}..{int(a.max())}")
    steps, rem = np.divmod(t, step_us)
    if rem.any():
        raise ProtocolError(f"event times must be multiples of the {step_us} µs step")
    t_lo, t_hi = int(t.min()), int(t.max())
    if t_lo < t_min_us or t_hi >= t_end_us:
        raise ProtocolError(f"event times {t_lo}..{t_hi} µs must lie in [{t_min_us}, "
                            f"{t_end_us}) µs: after the previous call, before t_end_us")
    key = steps * 512 + a.astype(np.int64)
    if n > 1 and bool((key[1:] < key[:-1]).any()):
        order = np.argsort(key, kind="stable")
        steps, a = steps[order], a[order]
    return np.ascontiguousarray(steps), np.ascontiguousarray(a, dtype=np.uint16)
