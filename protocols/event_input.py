"""Checks and conversion of event arrays handed to an encoder (shared by serial and CAN)."""

from __future__ import annotations

import numba
import numpy as np

from protocols.constants import N_CHANNELS
from protocols.errors import ProtocolError

# encoder state slots, the serial and the CAN encoders' alike
E_SEQ, E_EPOCH, E_SYNC_VALID, E_SYNC_BASE, E_EVENTS, E_STEP_US, E_LAST_SYNC, E_VERSION = range(8)
E_SIZE = 8


def idle_sync_step(st: np.ndarray, t_end_us: int, step_us: int, sync_us: int) -> int | None:
    """The step of the SYNC an encoder with state ``st`` sends at a flush without events up
    to ``t_end_us`` (µs): the end step once its last SYNC base is ``sync_us`` old, else
    None (also before any SYNC)."""
    end_step = int(t_end_us) // step_us
    if st[E_SYNC_VALID] and end_step - st[E_LAST_SYNC] >= sync_us // step_us:
        return end_step
    return None

_OK, _UNSORTED, _BAD_ADDR, _NOT_MULTIPLE, _OUT_OF_RANGE = 0, 1, -1, -2, -3


def check_step_us(step_us: int) -> int:
    """Return ``step_us`` if it is a valid time step (1..65535 µs), else raise ProtocolError."""
    if not 1 <= int(step_us) <= 0xFFFF:
        raise ProtocolError(f"time step {step_us} µs is outside 1..65535 µs; use e.g. 100")
    return int(step_us)


@numba.njit(cache=True, nogil=True)
def _convert(t: np.ndarray, a: np.ndarray, step_us: int, t_min: int, t_end: int,
             n_channels: int, steps: np.ndarray, addr: np.ndarray) -> int:
    order_ok = True
    prev_s = -1
    prev_a = -1
    for i in range(t.shape[0]):
        ti = t[i]
        ai = int(a[i])
        if ai < 0 or ai >= n_channels:
            return _BAD_ADDR
        if ti % step_us:
            return _NOT_MULTIPLE
        if ti < t_min or ti >= t_end:
            return _OUT_OF_RANGE
        s = ti // step_us
        steps[i] = s
        addr[i] = ai
        if s < prev_s or (s == prev_s and ai < prev_a):
            order_ok = False
        prev_s = s
        prev_a = ai
    return _OK if order_ok else _UNSORTED


def event_steps(events: np.ndarray, step_us: int, t_end_us: int, t_min_us: int,
                n_channels: int = N_CHANNELS) -> tuple[np.ndarray, np.ndarray]:
    """Return (time in steps int64, address uint32) of ``events``, sorted by (time, address).

    Raises ProtocolError if an address is outside 0..n_channels-1, a time is not a multiple of
    ``step_us``, is before ``t_min_us`` (the end of the previous call) or not before
    ``t_end_us``.
    """
    names = events.dtype.names
    if names is None or "t" not in names or "addr" not in names:
        raise ProtocolError("events must be an EVENT_DTYPE array (fields t, addr); "
                            "build it with skinhil.events.make_events")
    n = events.shape[0]
    steps = np.empty(n, dtype=np.int64)
    addr = np.empty(n, dtype=np.uint32)
    if n == 0:
        return steps, addr
    code = _convert(events["t"], events["addr"], step_us, t_min_us, t_end_us, n_channels,
                    steps, addr)
    if code == _BAD_ADDR:
        raise ProtocolError(f"an event address is outside 0..{n_channels - 1}")
    if code == _NOT_MULTIPLE:
        raise ProtocolError(f"event times must be multiples of the {step_us} µs step")
    if code == _OUT_OF_RANGE:
        raise ProtocolError(f"event times must lie in [{t_min_us}, {t_end_us}) µs: after the "
                            "previous call's t_end_us and before this call's")
    if code == _UNSORTED:
        order = np.lexsort((addr, steps))
        steps, addr = steps[order], addr[order]
    if n > 1 and np.any((steps[1:] == steps[:-1]) & (addr[1:] == addr[:-1])):
        raise ProtocolError("two events share a channel and a step: a channel spikes at most "
                            "once per step; merge the duplicates before encoding")
    return steps, addr
