"""Compiled inner loops of the CAN codec: events frames out, whole frame batches in.

Layouts are those of SPEC.md §5 (narrow, version 3) and §9 (wide, version 4: WIDE_EVENTS
frames of 24-bit words). State and counters are int64 arrays; the slot names are the
constants below (counter slots are shared with :mod:`protocols.serial_kernels`).
"""

from __future__ import annotations

import numba
import numpy as np

from protocols.constants import MAX_CAN_CLASS, N_CHANNELS, PROTOCOL_VERSION, WIDE_VERSION
from protocols.event_input import (
    E_EPOCH,
    E_EVENTS,
    E_LAST_SYNC,
    E_SEQ,
    E_STEP_US,
    E_SYNC_BASE,
    E_SYNC_VALID,
    E_VERSION,
)
from protocols.serial_kernels import (  # noqa: F401  (counter slots CAN shares, read by can_codec)
    C_CMD_GAPS,
    C_CMD_LOST,
    C_DUPS,
    C_EVENTS,
    C_FRAMES_OK,
    C_GAPS,
    C_LOST,
    C_MALFORMED,
    C_SYNCS,
    C_UNTIMED,
    MAX_TIME_US,
    SEQ_NEW,
    WIDE_ITEM_BYTES,
    WIDE_MAX_DELTA,
    get_le,
    is_known_version,
    put_le,
    take_base,
    take_seq,
)
from protocols.versions import MAX_CHANNELS

CLS_COMMAND, CLS_ACK, CLS_SYNC, CLS_STATUS, CLS_MARKER, CLS_EVENTS, CLS_WIDE = range(1, 8)
"""Frame classes: the 11-bit ID is ``class << 4 | board_id``. CLS_WIDE (wide events) belongs
to a board only once it announced version 4 (a version-4 SYNC)."""
CLS_SESSION, CLS_STIMULUS, CLS_RUN_END, CLS_SUITE, CLS_TASK = 8, 9, 10, 11, 12
"""Session-record classes (SPEC.md §5.8): each record's payload in chunks, one per frame;
classes 13..15 are reserved for future records (foreign frames here)."""
MAX_CHUNKS = 16
"""Most frames of one session record (the classic chunk index has 4 bits)."""

CLASSIC_MAX_EVENTS = 4
FD_MAX_EVENTS = 40
CLASSIC_MAX_WIDE = 2
"""Wide events per classic frame (2 + 2 x 3 bytes)."""
FD_MAX_WIDE = 20
"""Wide events per 64-byte FD frame (4 + 20 x 3 bytes)."""
EVENTS_LEN_CLASSIC = 8
"""Data length (bytes) of every classic EVENTS / WIDE_EVENTS frame: header and slots."""
EVENTS_LEN_FD = 64
"""Data length (bytes) of every FD EVENTS / WIDE_EVENTS frame: header and slots."""
EMPTY_SLOT = 0xFFF
"""An unused 12-bit event slot (address 511): slots after a frame's last event hold it."""
EMPTY_WIDE_SLOT = 0xFFFFFF
"""An unused 24-bit wide slot (the all-ones address)."""
CLASSIC_MAX_OFFSET = (1 << 9) - 1
FD_MAX_OFFSET = (1 << 15) - 1
EPOCH_MOD = 8
"""SYNC epochs count modulo 8; a sequence gap of 8 frames or more invalidates the time base."""
CLASSIC_SEQ_MOD = 16
FD_SEQ_MOD = 256
C_FOREIGN = 14
"""Counter slot of frames with another board's or an unknown ID (after the serial slots,
:data:`protocols.serial_kernels.C_CMD_GAPS` and the rest, which CAN shares)."""
C_SIZE = 15

# decoder state slots (D_VERSION: of the last SYNC; D_VERSIONS: bit v set once one was seen)
# D_LAST_T / D_LAST_A: time (µs) and address of the last event decoded, once D_HAVE_LAST
(D_HAVE_SEQ, D_SEQ, D_SYNC_VALID, D_EPOCH, D_BASE, D_STEP_US, D_HAVE_CMD_SEQ,
 D_CMD_SEQ, D_VERSION, D_VERSIONS, D_CAND, D_HAVE_CAND, D_HAVE_LAST, D_LAST_T,
 D_LAST_A) = range(15)
D_SIZE = 15


@numba.njit(cache=True, nogil=True)
def encode_sync(st: np.ndarray, base: int, fd: bool, out: np.ndarray, pos: int) -> int:
    """Write a SYNC frame's data with time base ``base`` (steps) at ``pos``; return its length."""
    epoch = (st[E_EPOCH] + 1) % EPOCH_MOD
    if fd:
        out[pos] = st[E_SEQ] & 0xFF
        out[pos + 1] = epoch | (st[E_VERSION] << 4)
        put_le(out, pos + 2, st[E_STEP_US], 2)
        put_le(out, pos + 4, base & ((1 << 48) - 1), 6)
        out[pos + 10] = 0
        out[pos + 11] = 0
        st[E_SEQ] = (st[E_SEQ] + 1) % FD_SEQ_MOD
        ln = 12
    else:
        out[pos] = (st[E_SEQ] & 0xF) | (epoch << 4) | (0x80 if st[E_VERSION] == WIDE_VERSION
                                                       else 0)
        put_le(out, pos + 1, st[E_STEP_US], 2)
        put_le(out, pos + 3, base & ((1 << 40) - 1), 5)
        st[E_SEQ] = (st[E_SEQ] + 1) % CLASSIC_SEQ_MOD
        ln = 8
    st[E_EPOCH] = epoch
    st[E_SYNC_VALID] = 1
    st[E_SYNC_BASE] = base
    st[E_LAST_SYNC] = base
    return ln


@numba.njit(cache=True, nogil=True)
def _put_slot(out: np.ndarray, bitpos: int, e: int, wide: bool) -> None:
    """Write one event slot (12-bit word, or 24-bit ``wide``) at bit ``bitpos`` of ``out``."""
    if wide:
        put_le(out, bitpos >> 3, e, WIDE_ITEM_BYTES)
        return
    p = bitpos >> 3
    if bitpos & 7:
        out[p] |= (e & 0xF) << 4
        out[p + 1] = e >> 4
    else:
        out[p] = e & 0xFF
        out[p + 1] = e >> 8


@numba.njit(cache=True, nogil=True)
def encode_events(steps: np.ndarray, addr: np.ndarray, st: np.ndarray, sync_every: int,
                  fd: bool, max_frames: int, out: np.ndarray, lens: np.ndarray,
                  kinds: np.ndarray) -> tuple[int, int]:
    """Write SYNC and EVENTS (or WIDE_EVENTS) frame data for sorted events into ``out``.

    Frames are filled: one closes only when it is full, when the next event's delta does
    not fit, or after the last event given; its slots after the last event are empty. At
    most ``max_frames`` events frames are written. Frame ``f`` has ``lens[f]`` bytes and
    class ``kinds[f]``, consecutive in ``out``. Returns ``(frames written, events consumed)``.
    """
    n = steps.shape[0]
    wide = st[E_VERSION] == WIDE_VERSION
    if wide:
        max_n = FD_MAX_WIDE if fd else CLASSIC_MAX_WIDE
        max_d = WIDE_MAX_DELTA
        cls = CLS_WIDE
        width = 24
        empty = EMPTY_WIDE_SLOT
        shift = 4
    else:
        max_n = FD_MAX_EVENTS if fd else CLASSIC_MAX_EVENTS
        max_d = 7
        cls = CLS_EVENTS
        width = 12
        empty = EMPTY_SLOT
        shift = 3
    max_off = FD_MAX_OFFSET if fd else CLASSIC_MAX_OFFSET
    hdr = 4 if fd else 2
    ln = EVENTS_LEN_FD if fd else EVENTS_LEN_CLASSIC
    pos = 0
    nf = 0
    frames = 0
    i = 0
    while i < n and frames < max_frames:
        base = steps[i]
        off = base - st[E_SYNC_BASE]
        if st[E_SYNC_VALID] == 0 or off > max_off or off >= sync_every:
            sl = encode_sync(st, base, fd, out, pos)
            lens[nf] = sl
            kinds[nf] = CLS_SYNC
            nf += 1
            pos += sl
            off = 0
        cur = base
        cnt = 0
        bitpos = 8 * (pos + hdr)
        for _ in range(max_n):
            if i < n and steps[i] - cur <= max_d:
                _put_slot(out, bitpos, (np.int64(addr[i]) << shift) | (steps[i] - cur), wide)
                cur = steps[i]
                cnt += 1
                i += 1
            else:
                _put_slot(out, bitpos, empty, wide)
            bitpos += width
        if fd:
            h = (st[E_SEQ] & 0xFF) | (st[E_EPOCH] << 8) | (cnt << 11) | (off << 17)
            put_le(out, pos, h, 4)
            st[E_SEQ] = (st[E_SEQ] + 1) % FD_SEQ_MOD
        else:
            h = (st[E_SEQ] & 0xF) | (st[E_EPOCH] << 4) | (off << 7)
            put_le(out, pos, h, 2)
            st[E_SEQ] = (st[E_SEQ] + 1) % CLASSIC_SEQ_MOD
        lens[nf] = ln
        kinds[nf] = cls
        nf += 1
        frames += 1
        pos += ln
        st[E_EVENTS] += cnt
    return nf, i


@numba.njit(cache=True, nogil=True)
def _event_at(blob: np.ndarray, o: int, k: int, hdr: int) -> np.int64:
    bit = 8 * hdr + 12 * k
    p = o + (bit >> 3)
    if bit & 7:
        return (np.int64(blob[p]) >> 4) | (np.int64(blob[p + 1]) << 4)
    return np.int64(blob[p]) | ((np.int64(blob[p + 1]) & 0xF) << 8)


@numba.njit(cache=True, nogil=True)
def _slot(blob: np.ndarray, o: int, k: int, hdr: int, wide: bool) -> np.int64:
    if wide:
        return np.int64(get_le(blob, o + hdr + WIDE_ITEM_BYTES * k, WIDE_ITEM_BYTES))
    return _event_at(blob, o, k, hdr)


@numba.njit(cache=True, nogil=True)
def _events_count(blob: np.ndarray, o: int, ln: int, fd: bool, wide: bool) -> np.int64:
    """Events in a valid EVENTS (or ``wide`` WIDE_EVENTS) frame, or -1 if its layout is
    invalid: the fixed length; events in the first slots (valid addresses), every slot after
    the last event empty; FD: the count field says how many."""
    if wide:
        slots, empty, shift, top = (FD_MAX_WIDE if fd else CLASSIC_MAX_WIDE,
                                    np.int64(EMPTY_WIDE_SLOT), 4, MAX_CHANNELS)
    else:
        slots, empty, shift, top = (FD_MAX_EVENTS if fd else CLASSIC_MAX_EVENTS,
                                    np.int64(EMPTY_SLOT), 3, N_CHANNELS)
    hdr = 4 if fd else 2
    if ln != (EVENTS_LEN_FD if fd else EVENTS_LEN_CLASSIC):
        return np.int64(-1)
    if fd:
        n = (np.int64(blob[o + 1]) >> 3) | ((np.int64(blob[o + 2]) & 1) << 5)
    else:
        n = np.int64(slots)
        for k in range(slots):
            if _slot(blob, o, k, hdr, wide) == empty:
                n = np.int64(k)
                break
    if n < 1 or n > slots:
        return np.int64(-1)
    for k in range(n):
        if (_slot(blob, o, k, hdr, wide) >> shift) >= top:
            return np.int64(-1)
    for k in range(n, slots):
        if _slot(blob, o, k, hdr, wide) != empty:
            return np.int64(-1)
    return n


@numba.njit(cache=True, nogil=True)
def _layout_ok(cls: int, blob: np.ndarray, o: int, ln: int, fd: bool) -> bool:
    """Whether a record frame of class ``cls`` has exactly its layout's length (SPEC.md §5:
    a longer frame is malformed too) and valid fields."""
    if cls == CLS_SYNC:
        if fd:
            return ln == 12 and is_known_version(blob[o + 1] >> 4) and (
                blob[o + 1] & 0x8) == 0 and get_le(blob, o + 2, 2) > 0 and (
                get_le(blob, o + 4, 6) < MAX_TIME_US // get_le(blob, o + 2, 2))
        return ln == 8 and get_le(blob, o + 1, 2) > 0
    if cls == CLS_STATUS:
        if fd:
            return ln == 64
        return ln == 8 and (blob[o] >> 4) <= 7
    if cls == CLS_MARKER:
        if fd:
            return ln == 12 and blob[o + 1] <= 1
        return ln == 8 and (blob[o] >> 4) <= 1
    if cls == CLS_ACK:
        return ln == 6
    if cls >= CLS_SESSION:  # chunk index: classic byte 0 bits 7..4, FD byte 1
        return ln == 64 and blob[o + 1] < MAX_CHUNKS if fd else ln == 8
    return ln == 8  # COMMAND


@numba.njit(cache=True, nogil=True)
def _epoch_offset(blob: np.ndarray, fo: int, fd: bool) -> tuple[int, int]:
    """The SYNC epoch and the offset (steps) of the EVENTS frame at ``blob[fo:]`` (§5.3)."""
    if fd:
        return blob[fo + 1] & 0x7, get_le(blob, fo + 2, 2) >> 1
    return (blob[fo] >> 4) & 0x7, get_le(blob, fo, 2) >> 7


@numba.njit(cache=True, nogil=True)
def _late_copy(st: np.ndarray, blob: np.ndarray, fo: int, fd: bool, wide: bool,
               hdr: int) -> bool:
    """Whether the EVENTS frame at ``blob[fo:]`` is timed in the current SYNC period and its
    first event (time, address) does not follow the last event decoded in it: a copy that
    came late (classic CAN's 4-bit sequence number cannot tell it from a new frame)."""
    if not st[D_HAVE_LAST] or st[D_SYNC_VALID] == 0:
        return False
    epoch, off = _epoch_offset(blob, fo, fd)
    if epoch != st[D_EPOCH]:
        return False
    if wide:
        word = np.int64(get_le(blob, fo + hdr, WIDE_ITEM_BYTES))
        delta, a = word & WIDE_MAX_DELTA, word >> 4
    else:
        e = _event_at(blob, fo, 0, hdr)
        delta, a = e & 7, e >> 3
    t = (st[D_BASE] + off + delta) * st[D_STEP_US]
    return bool(t < st[D_LAST_T] or (t == st[D_LAST_T] and a <= st[D_LAST_A]))


@numba.njit(cache=True, nogil=True)
def decode_frames(ids: np.ndarray, lens: np.ndarray, blob: np.ndarray, board: int, fd: bool,
                  st: np.ndarray, c: np.ndarray) -> tuple[
                      np.ndarray, np.ndarray, int, np.ndarray, int]:
    """Decode a batch of frames (IDs, data lengths, concatenated data) in order.

    Returns ``(t_us, addr, n_events, rec_index, n_records)``; ``rec_index[r] = (frame,
    class, events decoded before it, time base in µs or -1)`` for record frames.
    """
    nf = ids.shape[0]
    cap = 0
    for f in range(nf):
        cap += lens[f]
    cap = (cap * 8) // 12 + 8
    out_t = np.empty(cap, dtype=np.int64)
    out_a = np.empty(cap, dtype=np.uint32)
    rec_ix = np.empty((nf + 1, 4), dtype=np.int64)
    seq_mod = FD_SEQ_MOD if fd else CLASSIC_SEQ_MOD
    hdr = 4 if fd else 2
    ne = 0
    nr = 0
    o = 0
    for f in range(nf):
        ln = lens[f]
        fo = o
        o += ln
        ident = ids[f]
        cls = ident >> 4
        wide_ok = st[D_VERSION] == WIDE_VERSION
        if ident < 0 or ident > 0x7FF or (ident & 0xF) != board or cls < 1 or (
                cls > MAX_CAN_CLASS or (cls == CLS_WIDE and not wide_ok)):
            c[C_FOREIGN] += 1
            continue
        if ln < 1 or (not fd and ln > 8):
            c[C_MALFORMED] += 1
            continue
        count = np.int64(0)
        if cls == CLS_EVENTS or cls == CLS_WIDE:
            count = _events_count(blob, fo, ln, fd, cls == CLS_WIDE)
            if count < 0:
                c[C_MALFORMED] += 1
                continue
        elif not _layout_ok(cls, blob, fo, ln, fd):
            c[C_MALFORMED] += 1
            continue
        if count and _late_copy(st, blob, fo, fd, cls == CLS_WIDE, hdr):
            c[C_DUPS] += 1  # its events do not follow the last decoded (SPEC §6, CAN)
            continue
        seq = blob[fo] & (seq_mod - 1)
        command = cls == CLS_COMMAND  # a host's counter: apart from the board's frames
        have, last = (D_HAVE_CMD_SEQ, D_CMD_SEQ) if command else (D_HAVE_SEQ, D_SEQ)
        if take_seq(st, c, have, last, D_SYNC_VALID, seq, seq_mod, command, 0,
                    EPOCH_MOD) != SEQ_NEW:
            continue
        c[C_FRAMES_OK] += 1
        if cls == CLS_EVENTS or cls == CLS_WIDE:
            epoch, off = _epoch_offset(blob, fo, fd)
            if st[D_SYNC_VALID] == 0 or epoch != st[D_EPOCH]:
                c[C_UNTIMED] += count
                continue
            t = st[D_BASE] + off
            step = st[D_STEP_US]
            for k in range(count):
                if cls == CLS_WIDE:
                    word = get_le(blob, fo + hdr + WIDE_ITEM_BYTES * k, WIDE_ITEM_BYTES)
                    t += word & WIDE_MAX_DELTA
                    out_a[ne] = word >> 4
                else:
                    e = _event_at(blob, fo, k, hdr)
                    t += e & 7
                    out_a[ne] = e >> 3
                out_t[ne] = t * step
                ne += 1
            if count:
                st[D_HAVE_LAST] = 1
                st[D_LAST_T] = out_t[ne - 1]
                st[D_LAST_A] = out_a[ne - 1]
        elif cls == CLS_SYNC:
            st[D_SYNC_VALID] = 1
            if fd:
                st[D_EPOCH] = blob[fo + 1] & 0x7
                st[D_VERSION] = blob[fo + 1] >> 4
                step, raw, bits = get_le(blob, fo + 2, 2), get_le(blob, fo + 4, 6), 48
            else:
                st[D_EPOCH] = (blob[fo] >> 4) & 0x7
                st[D_VERSION] = WIDE_VERSION if blob[fo] & 0x80 else PROTOCOL_VERSION
                step, raw, bits = get_le(blob, fo + 1, 2), get_le(blob, fo + 3, 5), 40
            st[D_VERSIONS] |= 1 << st[D_VERSION]
            st[D_HAVE_LAST] = 0  # the order check spans one SYNC period (SPEC §6, CAN)
            if st[D_STEP_US]:
                st[D_SYNC_VALID] = take_base(st, D_BASE, D_CAND, D_HAVE_CAND, raw, bits)
            else:
                st[D_BASE] = raw
            st[D_STEP_US] = step
            c[C_SYNCS] += 1
        else:
            rec_ix[nr, 0] = f
            rec_ix[nr, 1] = cls
            rec_ix[nr, 2] = c[C_EVENTS] + ne
            rec_ix[nr, 3] = st[D_BASE] * st[D_STEP_US] if st[D_STEP_US] > 0 else -1
            nr += 1
    c[C_EVENTS] += ne
    return out_t, out_a, ne, rec_ix, nr
