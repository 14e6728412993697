"""Compiled inner loops of the serial codec: events packets out, whole byte streams in.

State and counters live in small int64 arrays so the loops run without Python objects; the
index constants below name their slots. Layouts are those of SPEC.md §3-§4 (narrow, version 3)
and §9 (wide, version 4: WIDE_EVENTS packets of 24-bit words).
"""

from __future__ import annotations

import numba
import numpy as np

from protocols.constants import BITMAP_BYTES, N_CHANNELS, PROTOCOL_VERSION, WIDE_VERSION
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
from protocols.framing import CRC_RESIDUE, cobs_decode, crc16, frame_into, suffix_checks
from protocols.versions import MAX_CHANNELS

T_EVENTS, T_SYNC, T_STATUS, T_MARKER, T_COMMAND, T_ACK, T_WIDE, T_SESSION = range(8)
"""Packet types (high three bits of byte 0); T_WIDE carries wide (version 4) events;
T_SESSION the session records (SPEC.md §3.7), their kind in byte 0 bits 4..0."""

K_SESSION, K_STIMULUS, K_RUN_END, K_SUITE, K_TASK = 0, 1, 2, 3, 4
"""Kinds of a T_SESSION packet (byte 0 bits 4..0); 5..31 are reserved (malformed here)."""
SESSION_BODY = 2 + 39
"""Body length of a SESSION packet (header and the 39-byte payload)."""
RUN_END_BODY = 2 + 7
"""Body length of a RUN_END packet."""
MAX_NAME_BYTES = 64
"""Longest stimulus name of a STIMULUS packet (bytes)."""
MAX_RUN_END_REASON = 3
"""Largest RUN_END reason (0 DURATION, 1 STOP, 2 SIGNAL, 3 ERROR)."""
MAX_SUITE_NAME_BYTES, MAX_UNIT_BYTES, MAX_CLASSES, MAX_TASK_ID = 32, 8, 24, 15
"""Longest suite / case name and unit (bytes), most classes of a TASK packet, largest task."""

WIDE_ITEM_BYTES = 3
"""A wide event word: 24 bits, little-endian: bits 3..0 delta, bits 23..4 address."""

WIDE_MAX_DELTA = 15
"""Largest step delta of a wide event word (4 bits)."""

MAX_TIME_US = 1 << 62
"""A SYNC whose base × step reaches this (µs) is malformed: event times stay far inside a
signed 64-bit integer (SPEC.md §6 rule 5)."""

MAX_MARKER_PHASE = 1
"""Largest MARKER phase (0 ONSET, 1 END); a larger one makes the packet malformed."""

BITMAP_ADDR = 511
"""Address field value of a bitmap word."""

MIN_BITMAP_EVENTS = (2 + BITMAP_BYTES) // 2 + 1
"""A step with at least this many distinct channels is sent as a bitmap (23)."""

MAX_BODY = 1024
"""Largest packet body (header + payload, CRC excluded) an encoder emits (bytes)."""

MAX_WIRE = MAX_BODY + 2 + (MAX_BODY + 2) // 254 + 2
"""Largest COBS-encoded packet (delimiter excluded); longer candidates hold garbage."""

EPOCH_MOD = 32
"""SYNC epochs count modulo this; a sequence gap this long invalidates the time base."""

BODY_LEN = np.array([-1, 11, 60, 13, 9, 6, -1, -1], dtype=np.int64)
"""Exact body length of each fixed-size packet type (-1: variable or invalid)."""

# decoder state slots (D_VERSIONS: bit v set once a SYNC of version v was received)
(D_HAVE_SEQ, D_SEQ, D_SYNC_VALID, D_EPOCH, D_BASE, D_STEP_US, D_VERSIONS, D_HAVE_CMD_SEQ,
 D_CMD_SEQ, D_CAND, D_HAVE_CAND) = range(11)
D_SIZE = 11
# decoder counter slots (LinkCounters fields of the same names)
(C_FRAMES_OK, C_CRC, C_MALFORMED, C_RESYNCS, C_DISCARDED, C_GAPS, C_LOST, C_DUPS,
 C_EVENTS, C_UNTIMED, C_SYNCS, C_CMD_GAPS, C_CMD_LOST, C_LATE) = range(14)
C_SIZE = 14

LATE_WINDOW = 8
"""A board packet 1..LATE_WINDOW sequence numbers behind the last one is late (reordered),
not a gap of 248..255 (SPEC.md §6 rule 4)."""


@numba.njit(cache=True, nogil=True)
def put_le(buf: np.ndarray, pos: int, value: int, n: int) -> None:
    """Write ``value`` as an ``n``-byte little-endian unsigned integer at ``buf[pos]``."""
    for k in range(n):
        buf[pos + k] = (value >> (8 * k)) & 0xFF


@numba.njit(cache=True, nogil=True)
def get_le(buf: np.ndarray, pos: int, n: int) -> int:
    """Read an ``n``-byte little-endian unsigned integer at ``buf[pos]``."""
    v = 0
    for k in range(n):
        v |= int(buf[pos + k]) << (8 * k)
    return v


@numba.njit(cache=True, nogil=True)
def unwrap_near(previous: int, raw: int, bits: int) -> int:
    """The value congruent to ``raw`` modulo ``2**bits`` nearest to ``previous``."""
    mod = 1 << bits
    delta = (raw - previous) % mod
    if delta >= mod >> 1:
        delta -= mod
    return previous + delta


BASE_JUMP_BITS = 4
"""A SYNC base further than 2**(width - BASE_JUMP_BITS) steps from the previous one is a jump
(a board restart or a damaged SYNC, SPEC.md §6 rule 5)."""


@numba.njit(cache=True, nogil=True)
def take_base(st: np.ndarray, i_base: int, i_cand: int, i_have_cand: int, raw: int,
              bits: int) -> bool:
    """Set the time base (``st[i_base]``, steps) from a SYNC's ``raw`` base (sent modulo
    ``2**bits``); return whether the time base is valid after it.

    The first SYNC is taken as sent. Later ones are unwrapped near the previous base; one
    that lands more than ``2**(bits - BASE_JUMP_BITS)`` steps away is a jump: it is held
    as a candidate (``st[i_cand]``) and the time base is invalid until a SYNC either
    continues the old base (the jump was damage) or lies near the candidate (a board
    restart: the base re-anchors there). One damaged SYNC thus never shifts later times.
    """
    jump = 1 << (bits - BASE_JUMP_BITS)
    prev = st[i_base]
    u = unwrap_near(prev, raw, bits)
    if abs(u - prev) <= jump:
        st[i_base] = u
        st[i_have_cand] = 0
        return True
    if st[i_have_cand]:
        v = unwrap_near(st[i_cand], raw, bits)
        if abs(v - st[i_cand]) <= jump:
            st[i_base] = v
            st[i_have_cand] = 0
            return True
    st[i_cand] = raw
    st[i_have_cand] = 1
    return False


SEQ_NEW, SEQ_DUPLICATE, SEQ_LATE = 0, 1, 2
"""Verdicts of :func:`take_seq` on a unit's sequence number."""


@numba.njit(cache=True, nogil=True)
def take_seq(st: np.ndarray, c: np.ndarray, have: int, last: int, sync_valid: int, seq: int,
             mod: int, command: bool, late_window: int, epoch_gap: int) -> int:
    """Check a packet's or frame's ``seq`` against the previous number (``st[last]``, valid
    once ``st[have]``) of one counter modulo ``mod`` (SPEC.md §6 rule 4; counter slots are
    this module's ``C_*``, which the CAN kernels share): a repeat is a duplicate; 1..``late_window``
    behind is late (both left uncounted in the sequence); otherwise a gap counts in the
    command counters (``command``) or the board's, where a gap of ``epoch_gap`` or more
    invalidates the time base (``st[sync_valid]``), and ``seq`` becomes the previous."""
    if st[have]:
        gap = (seq - st[last] - 1) % mod
        if gap == mod - 1:
            c[C_DUPS] += 1
            return SEQ_DUPLICATE
        if gap >= mod - 1 - late_window:
            c[C_LATE] += 1
            return SEQ_LATE
        if gap and command:
            c[C_CMD_GAPS] += 1
            c[C_CMD_LOST] += gap
        elif gap:
            c[C_GAPS] += 1
            c[C_LOST] += gap
            if gap >= epoch_gap:
                st[sync_valid] = 0
    st[have] = 1
    st[last] = seq
    return SEQ_NEW


@numba.njit(cache=True, nogil=True)
def encode_sync(st: np.ndarray, base: int, pkt: np.ndarray, out: np.ndarray, pos: int) -> int:
    """Append a SYNC packet with time base ``base`` (steps); update ``st``; return the end."""
    epoch = (st[E_EPOCH] + 1) % EPOCH_MOD
    pkt[0] = (T_SYNC << 5) | epoch
    pkt[1] = st[E_SEQ] & 0xFF
    pkt[2] = st[E_VERSION]
    put_le(pkt, 3, st[E_STEP_US], 2)
    put_le(pkt, 5, base & ((1 << 48) - 1), 6)
    st[E_SEQ] = (st[E_SEQ] + 1) & 0xFF
    st[E_EPOCH] = epoch
    st[E_SYNC_VALID] = 1
    st[E_SYNC_BASE] = base
    st[E_LAST_SYNC] = base
    return frame_into(pkt, 11, out, pos)


@numba.njit(inline="always")
def _open_events_packet(st: np.ndarray, base: int, sync_every: int, ptype: int,
                        pkt: np.ndarray, out: np.ndarray, pos: int) -> int:
    """Write the header of an events packet of type ``ptype`` whose first event is at step
    ``base`` into ``pkt``, after a SYNC into ``out`` at ``pos`` when the offset needs one;
    return the new end of ``out``."""
    if (st[E_SYNC_VALID] == 0 or base - st[E_SYNC_BASE] > 0xFFFF
            or base - st[E_SYNC_BASE] >= sync_every):
        pos = encode_sync(st, base, pkt, out, pos)
    off = base - st[E_SYNC_BASE]
    pkt[0] = (ptype << 5) | st[E_EPOCH]
    pkt[1] = st[E_SEQ] & 0xFF
    pkt[2] = off & 0xFF
    pkt[3] = off >> 8
    return pos


@numba.njit(inline="always")
def _close_events_packet(st: np.ndarray, pkt: np.ndarray, ln: int, count: int,
                         out: np.ndarray, pos: int) -> int:
    """Frame the events packet ``pkt[:ln]`` of ``count`` events into ``out`` at ``pos``,
    advance the sequence number and the events count; return the new end of ``out``."""
    pos = frame_into(pkt, ln, out, pos)
    st[E_SEQ] = (st[E_SEQ] + 1) & 0xFF
    st[E_EVENTS] += count
    return pos


@numba.njit(cache=True, nogil=True)
def encode_events(steps: np.ndarray, addr: np.ndarray, st: np.ndarray, sync_every: int,
                  max_packets: int, out: np.ndarray) -> tuple[int, int]:
    """Append EVENTS packets (and the SYNCs they need) for sorted events.

    ``steps`` are event times in steps (sorted), ``addr`` their channels. Packets are
    filled: one closes only when the body is full, when the next delta does not fit, or
    after the last event given; at most ``max_packets`` events packets are written. A SYNC
    is sent before a packet whose base is ``sync_every`` steps or more after the last SYNC
    (or out of the 16-bit offset range). A version-4 encoder (``st[E_VERSION]``) writes
    WIDE_EVENTS packets instead. Returns ``(end in out, events consumed)``.
    """
    if st[E_VERSION] == WIDE_VERSION:
        return _encode_wide(steps, addr, st, sync_every, max_packets, out)
    n = steps.shape[0]
    pkt = np.empty(MAX_BODY + 8, dtype=np.uint8)
    seen = np.zeros(N_CHANNELS, dtype=np.bool_)
    pos = 0
    i = 0
    packets = 0
    while i < n and packets < max_packets:
        base = steps[i]
        pos = _open_events_packet(st, base, sync_every, T_EVENTS, pkt, out, pos)
        ln = 4
        cur = base
        count = 0
        while i < n:
            s = steps[i]
            d = s - cur
            if d > 127:
                break
            j = i + 1
            while j < n and steps[j] == s:
                j += 1
            cnt = j - i
            bitmap = False
            if cnt >= MIN_BITMAP_EVENTS and ln + 2 + BITMAP_BYTES <= MAX_BODY:
                bitmap = True
                for k in range(i, j):
                    if seen[addr[k]]:
                        bitmap = False
                    seen[addr[k]] = True
                for k in range(i, j):
                    seen[addr[k]] = False
            if bitmap:
                w = (BITMAP_ADDR << 7) | d
                pkt[ln] = w & 0xFF
                pkt[ln + 1] = w >> 8
                for k in range(BITMAP_BYTES):
                    pkt[ln + 2 + k] = 0
                for k in range(i, j):
                    a = addr[k]
                    pkt[ln + 2 + (a >> 3)] |= 1 << (a & 7)
                ln += 2 + BITMAP_BYTES
                count += cnt
                i = j
            else:
                room = (MAX_BODY - ln) // 2
                if room <= 0:
                    break
                k = min(cnt, room)
                w = (np.int64(addr[i]) << 7) | d
                pkt[ln] = w & 0xFF
                pkt[ln + 1] = w >> 8
                for q in range(1, k):
                    w = np.int64(addr[i + q]) << 7
                    pkt[ln + 2 * q] = w & 0xFF
                    pkt[ln + 2 * q + 1] = w >> 8
                ln += 2 * k
                count += k
                i += k
                if k < cnt:
                    cur = s
                    break
            cur = s
        pos = _close_events_packet(st, pkt, ln, count, out, pos)
        packets += 1
    return pos, i


@numba.njit(cache=True, nogil=True)
def _encode_wide(steps: np.ndarray, addr: np.ndarray, st: np.ndarray, sync_every: int,
                 max_packets: int, out: np.ndarray) -> tuple[int, int]:
    """:func:`encode_events` for version 4: WIDE_EVENTS packets of 24-bit words."""
    n = steps.shape[0]
    pkt = np.empty(MAX_BODY + 8, dtype=np.uint8)
    pos = 0
    i = 0
    packets = 0
    while i < n and packets < max_packets:
        base = steps[i]
        pos = _open_events_packet(st, base, sync_every, T_WIDE, pkt, out, pos)
        ln = 4
        cur = base
        count = 0
        while i < n and ln + WIDE_ITEM_BYTES <= MAX_BODY:
            s = steps[i]
            d = s - cur
            if d > WIDE_MAX_DELTA:
                break
            put_le(pkt, ln, (np.int64(addr[i]) << 4) | d, WIDE_ITEM_BYTES)
            ln += WIDE_ITEM_BYTES
            cur = s
            count += 1
            i += 1
        pos = _close_events_packet(st, pkt, ln, count, out, pos)
        packets += 1
    return pos, i


@numba.njit(cache=True, nogil=True)
def is_known_version(v: int) -> bool:
    """Whether ``v`` is a protocol version the decoders read (3 narrow, 4 wide)."""
    return v == PROTOCOL_VERSION or v == WIDE_VERSION


@numba.njit(cache=True, nogil=True)
def session_ok(dec: np.ndarray, m: int) -> bool:
    """Whether ``dec[:m]`` is a valid session-record body (type 7, SPEC.md §3.7)."""
    kind = dec[0] & 0x1F
    if kind == K_SESSION:
        if m != SESSION_BODY or not is_known_version(dec[8]) or get_le(dec, 13, 2) == 0:
            return False
        return (get_le(dec, 23, 4) & 0x7FFFFFFF) <= 0x7F800000  # the SNR is not a NaN
    if kind == K_STIMULUS:
        return m >= 8 and 1 <= dec[6] <= MAX_NAME_BYTES and m == 7 + dec[6]
    if kind == K_RUN_END:
        return m == RUN_END_BODY and dec[8] <= MAX_RUN_END_REASON
    if kind == K_SUITE:  # version, task records, name length n, case length m, names
        if m < 7 or dec[5] > MAX_SUITE_NAME_BYTES or dec[6] > MAX_SUITE_NAME_BYTES:
            return False
        if (dec[5] == 0) != (dec[6] == 0) or (dec[5] == 0 and get_le(dec, 2, 2) != 0):
            return False
        return m == 7 + dec[5] + dec[6]
    if kind == K_TASK:  # task, class count k, tolerance, unit length u, unit, classes
        if m < 9 or dec[2] > MAX_TASK_ID or dec[3] > MAX_CLASSES or dec[8] > MAX_UNIT_BYTES:
            return False
        if m != 9 + dec[8] + 4 * dec[3] or get_le(dec, 4, 4) >= 0x7F800000:
            return False  # the tolerance is >= 0 and finite
        for c in range(9 + dec[8], m, 4):
            if (get_le(dec, c, 4) & 0x7FFFFFFF) > 0x7F800000:  # a NaN class
                return False
        return True
    return False


@numba.njit(cache=True, nogil=True)
def check_body(dec: np.ndarray, m: int) -> int:
    """Number of events in a valid body ``dec[:m]`` (0 for record packets), -1 if invalid."""
    if m < 2:
        return -1
    typ = dec[0] >> 5
    if typ == T_WIDE:
        if m < 4 + WIDE_ITEM_BYTES or (m - 4) % WIDE_ITEM_BYTES:
            return -1
        last = -1
        for k in range(4, m, WIDE_ITEM_BYTES):
            word = get_le(dec, k, WIDE_ITEM_BYTES)
            a = word >> 4
            if a >= MAX_CHANNELS or (word & WIDE_MAX_DELTA == 0 and a <= last):
                return -1
            last = a
        return (m - 4) // WIDE_ITEM_BYTES
    if typ == T_SESSION:
        return 0 if session_ok(dec, m) else -1
    if typ != T_EVENTS:
        if BODY_LEN[typ] != m:
            return -1
        if typ == T_SYNC and (not is_known_version(dec[2]) or get_le(dec, 3, 2) == 0
                              or get_le(dec, 5, 6) >= MAX_TIME_US // get_le(dec, 3, 2)):
            return -1
        if typ == T_MARKER and dec[12] > MAX_MARKER_PHASE:
            return -1
        return 0
    if m <= 4:  # an EVENTS packet holds at least one event (SPEC.md §3.1)
        return -1
    k = 4
    count = 0
    last = -1  # channel of the previous event in the current step (-1: none yet)
    while k < m:
        if k + 2 > m:
            return -1
        w = np.int64(dec[k]) | (np.int64(dec[k + 1]) << 8)
        a = int(w >> 7)
        if w & 0x7F:
            last = -1
        if a < N_CHANNELS:
            if a <= last:  # channels of one step ascend strictly (SPEC.md §3.1)
                return -1
            last = a
            count += 1
            k += 2
        elif a == BITMAP_ADDR:
            if (k + 2 + BITMAP_BYTES > m or dec[k + 1 + BITMAP_BYTES] & 0xFC
                    or last >= 0):
                return -1
            last = N_CHANNELS  # a bitmap holds its whole step
            before = count
            for q in range(k + 2, k + 2 + BITMAP_BYTES):
                v = dec[q]
                while v:
                    count += 1
                    v &= v - 1
            if count == before:  # an empty bitmap (SPEC.md §3.1)
                return -1
            k += 2 + BITMAP_BYTES
        else:
            return -1
    return count


@numba.njit(cache=True, nogil=True)
def try_frame(buf: np.ndarray, a: int, b: int, dec: np.ndarray) -> int:
    """Decode candidate ``buf[a:b]``: body length, -1 (bad COBS/CRC) or -2 (bad layout)."""
    n = cobs_decode(buf, a, b, dec)
    if n < 4 or crc16(dec, 0, n) != CRC_RESIDUE:
        return -1
    if n - 2 > MAX_BODY or check_body(dec, n - 2) < 0:
        return -2
    return n - 2


@numba.njit(cache=True, nogil=True)
def _grown(arr: np.ndarray, need: int) -> np.ndarray:
    """``arr`` if it holds ``need`` rows, else a copy with at least twice its rows."""
    if arr.shape[0] >= need:
        return arr
    out = np.empty((max(need, 2 * arr.shape[0]),) + arr.shape[1:], dtype=arr.dtype)
    out[:arr.shape[0]] = arr
    return out


@numba.njit(cache=True, nogil=True)
def decode_stream(buf: np.ndarray, st: np.ndarray, c: np.ndarray) -> tuple[
        np.ndarray, np.ndarray, int, np.ndarray, np.ndarray, int]:
    """Decode every zero-terminated candidate in ``buf`` (which ends with a zero).

    Returns ``(t_steps, addr, n_events, rec_bytes, rec_index, n_records)`` where event times
    are in µs; ``rec_index[r] = (offset, length, events decoded before it)`` of record ``r``.
    Time and memory are linear in ``len(buf)``: a damaged candidate is resynchronised by one
    pass over its suffixes (:func:`suffix_checks`), and the outputs grow with what decodes
    (garbage costs no more than a few scratch arrays of one candidate's size).
    """
    n = buf.shape[0]
    out_t = np.empty(64, dtype=np.int64)
    out_a = np.empty(64, dtype=np.uint32)
    rec = np.empty(256, dtype=np.uint8)
    rec_ix = np.empty((8, 3), dtype=np.int64)
    dec = np.empty(MAX_WIRE + 8, dtype=np.uint8)
    prefix = np.empty(MAX_WIRE + 8, dtype=np.int64)
    length = np.empty(MAX_WIRE + 8, dtype=np.int64)
    reg = np.empty(MAX_WIRE + 8, dtype=np.int64)
    passes = np.empty(MAX_WIRE + 8, dtype=np.bool_)
    ne = 0
    nr = 0
    rpos = 0
    start = 0
    for i in range(n):
        if buf[i] != 0:
            continue
        a = start
        b = i
        start = i + 1
        if b == a:
            continue
        m = -1
        first = a
        if b - a > MAX_WIRE:
            c[C_CRC] += 1
            c[C_DISCARDED] += b - MAX_WIRE - a
            first = b - MAX_WIRE
            a = first - 1  # the window start itself is a suffix candidate
        else:
            m = try_frame(buf, a, b, dec)
            if m < 0:
                if m == -2:
                    c[C_MALFORMED] += 1
                else:
                    c[C_CRC] += 1
        if m < 0:
            # resynchronise inside the candidate: the longest suffix that is a good frame
            suffix_checks(buf, first, b, prefix, length, reg, passes)
            for k in range(a + 1, b):
                if not passes[k - first]:
                    continue
                m = try_frame(buf, k, b, dec)
                if m >= 0:
                    c[C_RESYNCS] += 1
                    c[C_DISCARDED] += k - first
                    break
            if m < 0:
                c[C_DISCARDED] += b - first
                continue
        seq = dec[1]
        typ = dec[0] >> 5
        command = typ == T_COMMAND  # a host's counter, kept apart from the board's (§6)
        have, last = (D_HAVE_CMD_SEQ, D_CMD_SEQ) if command else (D_HAVE_SEQ, D_SEQ)
        verdict = take_seq(st, c, have, last, D_SYNC_VALID, seq, 256, command,
                           0 if command else LATE_WINDOW, EPOCH_MOD)
        if verdict == SEQ_LATE and (typ == T_EVENTS or typ == T_WIDE):
            c[C_UNTIMED] += check_body(dec, m)
        if verdict != SEQ_NEW:
            continue
        c[C_FRAMES_OK] += 1
        if typ == T_EVENTS or typ == T_WIDE:
            if st[D_SYNC_VALID] == 0 or (dec[0] & 0x1F) != st[D_EPOCH]:
                c[C_UNTIMED] += check_body(dec, m)
                continue
        if typ == T_EVENTS or typ == T_WIDE:
            grow = ne + check_body(dec, m)
            out_t = _grown(out_t, grow)
            out_a = _grown(out_a, grow)
        if typ == T_WIDE:
            t = st[D_BASE] + dec[2] + (np.int64(dec[3]) << 8)
            step = st[D_STEP_US]
            for k in range(4, m, WIDE_ITEM_BYTES):
                word = get_le(dec, k, WIDE_ITEM_BYTES)
                t += word & WIDE_MAX_DELTA
                out_t[ne] = t * step
                out_a[ne] = word >> 4
                ne += 1
        elif typ == T_EVENTS:
            t = st[D_BASE] + dec[2] + (np.int64(dec[3]) << 8)
            step = st[D_STEP_US]
            k = 4
            while k < m:
                w = np.int64(dec[k]) | (np.int64(dec[k + 1]) << 8)
                t += w & 0x7F
                ad = w >> 7
                if ad < N_CHANNELS:
                    out_t[ne] = t * step
                    out_a[ne] = ad
                    ne += 1
                    k += 2
                else:
                    for q in range(BITMAP_BYTES):
                        v = dec[k + 2 + q]
                        bit = 0
                        while v:
                            if v & 1:
                                out_t[ne] = t * step
                                out_a[ne] = 8 * q + bit
                                ne += 1
                            v >>= 1
                            bit += 1
                    k += 2 + BITMAP_BYTES
        elif typ == T_SYNC:
            st[D_SYNC_VALID] = 1
            st[D_EPOCH] = dec[0] & 0x1F
            raw = get_le(dec, 5, 6)
            if st[D_STEP_US]:
                st[D_SYNC_VALID] = take_base(st, D_BASE, D_CAND, D_HAVE_CAND, raw, 48)
            else:
                st[D_BASE] = raw
            st[D_STEP_US] = get_le(dec, 3, 2)
            st[D_VERSIONS] |= 1 << dec[2]
            c[C_SYNCS] += 1
        else:
            rec = _grown(rec, rpos + m)
            rec_ix = _grown(rec_ix, nr + 1)
            rec[rpos:rpos + m] = dec[:m]
            rec_ix[nr, 0] = rpos
            rec_ix[nr, 1] = m
            rec_ix[nr, 2] = c[C_EVENTS] + ne
            rpos += m
            nr += 1
    c[C_EVENTS] += ne
    return out_t, out_a, ne, rec, rec_ix, nr
