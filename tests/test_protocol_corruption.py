"""Corrupted links: the decoders never raise or hang, decode every undamaged frame, and count
losses exactly where SPEC.md §7 says they are exact; in the narrow format (the 6x6 skin's 338
channels) and the wide one (a 32x32 skin's 15,730 channels, SPEC.md §9)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from protocol_examples import distinct_events

from protocols import CanDecoder, CanEncoder, CanFrame, SerialDecoder, SerialEncoder, Status
from protocols.session_layout import CLASS_OF_KIND
from skinhil.events import EVENT_DTYPE

SETTINGS = settings(max_examples=100, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
N_CALLS = 60
STATUS_EVERY = 15
CHANNELS = [338, 15_730]
"""Channel counts: the narrow format (6x6 skin) and the wide one (32x32 skin)."""
SERIAL_EVENT_TYPES = (0, 6)
"""Serial packet types that carry events: EVENTS (narrow) and WIDE_EVENTS."""
CAN_EVENT_CLASSES = (6, 7)
"""CAN frame classes that carry events: EVENTS (narrow) and WIDE_EVENTS."""


def spikes(seed: int, rate_per_ms: float = 12.0, n_channels: int = 338) -> list[np.ndarray]:
    """Events of N_CALLS one-millisecond flushes (Poisson, 100 µs steps)."""
    rng = np.random.default_rng(seed)
    calls = []
    for c in range(N_CALLS):
        n = rng.poisson(rate_per_ms)
        t = np.sort(rng.integers(0, 10, n)) * 100 + c * 1000
        a = rng.integers(0, n_channels, n)
        calls.append(distinct_events(t, a))
    return calls


def cobs_type(packet: bytes) -> int:
    """Packet type (SPEC.md §3) of one clean COBS packet: the first decoded byte's top bits."""
    first = packet[1] if packet[0] > 1 else 0
    return first >> 5


def serial_packets(seed: int, n_channels: int = 338) -> list[tuple[int, bytes, np.ndarray | None]]:
    """(type, bytes incl. delimiter, events of an events packet) of a board stream with a
    status every STATUS_EVERY ms and at the end."""
    enc = SerialEncoder(sync_us=5000, n_channels=n_channels)
    out: list[tuple[int, bytes, np.ndarray | None]] = []
    sent = 0
    for c, ev in enumerate(spikes(seed, n_channels=n_channels)):
        data = enc.events(ev, (c + 1) * 1000)
        pkts = [p + b"\0" for p in data.split(b"\0")[:-1]]
        for p in pkts:
            typ = cobs_type(p)
            out.append((typ, p, ev if typ in SERIAL_EVENT_TYPES else None))
        sent += len(ev)
        if (c + 1) % STATUS_EVERY == 0:
            out.append((2, enc.status(Status((c + 1) * 1000, sent, sent, 0, 0, 0, 0, True)),
                        None))
    return out


def damage(p: bytes, op: int, pos: int, byte: int) -> bytes:
    body = p[:-1]
    i = 1 + pos % max(1, len(body) - 1)
    if op == 0:
        j = pos % len(body)
        return body[:j] + bytes([body[j] ^ (1 << (byte % 8))]) + body[j + 1:] + b"\0"
    if op == 1:
        return body[:i] + body[i + 1:] + b"\0"
    if op == 2:
        return body[:i] + bytes([byte]) + body[i:] + b"\0"
    if op == 3:
        return body[:i] + b"\0" + body[i:] + b"\0"
    if op == 4:
        return body[:i] + b"\0"
    return body + bytes([byte | 1])  # delimiter lost: runs into the next packet


@pytest.mark.parametrize("n_channels", CHANNELS)
@SETTINGS
@given(seed=st.integers(0, 10_000),
       hits=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 5),
                               st.integers(0, 10_000), st.integers(0, 255)), max_size=10),
       noise=st.lists(st.tuples(st.integers(0, 10_000), st.binary(min_size=1, max_size=40)),
                      max_size=5),
       chunk=st.integers(1, 500))
def test_serial_corruption(n_channels: int, seed: int, hits: list, noise: list,
                           chunk: int) -> None:
    pkts = serial_packets(seed, n_channels)
    last = len(pkts) - 2  # the first packet and the final status stay intact
    damaged: dict[int, tuple[int, int, int]] = {}
    for where, op, pos, byte in hits:
        damaged[1 + where % last] = (op, pos, byte)
    noise_at = {where % len(pkts): junk for where, junk in noise}
    stream = bytearray()
    for i, (_, p, _) in enumerate(pkts):
        if i in noise_at:
            stream += noise_at[i]
        stream += damage(p, *damaged[i]) if i in damaged else p
    dec = SerialDecoder()
    got, records = [], []
    for k in range(0, len(stream), chunk):
        res = dec.feed(bytes(stream[k:k + chunk]))
        got.append(res.events)
        records += res.records
    # expectation from the spec: an EVENTS packet is timed iff it and its SYNC are intact
    expected, sync_ok, lost, first_status = [], False, 0, None
    for i, (typ, _, ev) in enumerate(pkts):
        ok = i not in damaged
        if typ == 1:
            sync_ok = ok
        elif typ in SERIAL_EVENT_TYPES:
            assert ev is not None
            if ok and sync_ok:
                expected.append(ev)
            elif first_status is not None:
                lost += len(ev)
        elif typ == 2 and ok and first_status is None:
            first_status = i
    c = dec.counters
    np.testing.assert_array_equal(np.concatenate(got), np.concatenate(expected or [
        np.empty(0, EVENT_DTYPE)]))
    assert c.frames_ok == len(pkts) - len(damaged)
    assert c.frames_lost == len(damaged)
    assert c.events_lost == lost
    assert len(records) == sum(1 for i, (t, _, _) in enumerate(pkts)
                               if t == 2 and i not in damaged)
    if damaged:
        assert c.crc_errors + c.malformed >= 1 and c.bytes_discarded > 0


@pytest.mark.parametrize("n_channels", CHANNELS)
@SETTINGS
@given(junk=st.binary(max_size=5000), chunk=st.integers(1, 700), seed=st.integers(0, 100))
def test_serial_random_bytes_then_clean_stream(n_channels: int, junk: bytes, chunk: int,
                                               seed: int) -> None:
    """Arbitrary bytes never raise; a clean stream after them decodes completely."""
    pkts = serial_packets(seed, n_channels)
    clean = b"".join(p for _, p, _ in pkts)
    data = junk + clean
    dec = SerialDecoder()
    got = [dec.feed(data[k:k + chunk]).events for k in range(0, len(data), chunk)]
    every = np.concatenate([ev for t, _, ev in pkts if t in SERIAL_EVENT_TYPES and ev is not None])
    decoded = np.concatenate(got)
    np.testing.assert_array_equal(decoded[len(decoded) - len(every):], every)


def test_serial_megabyte_of_noise_is_fast_and_harmless() -> None:
    data = np.random.default_rng(1).integers(0, 256, 1 << 20, dtype=np.uint8).tobytes()
    dec = SerialDecoder()
    t0 = time.perf_counter()
    for k in range(0, len(data), 4096):
        dec.feed(data[k:k + 4096])
    assert time.perf_counter() - t0 < 10.0
    assert dec.counters.bytes_discarded > 0.99 * len(data)


def events_in_frame(f: CanFrame, fd: bool) -> int:
    """Events in an events frame (SPEC.md §5.3, §9.3): the DLC (classic) or the count field
    (FD)."""
    if fd:
        return (int.from_bytes(f.data[:4], "little") >> 11) & 0x3F
    if f.arbitration_id >> 4 == 7:
        return {5: 1, 8: 2}[len(f.data)]
    return {4: 1, 5: 2, 7: 3, 8: 4}[len(f.data)]


def can_frames(seed: int, fd: bool,
               n_channels: int = 338) -> list[tuple[int, CanFrame, np.ndarray | None]]:
    enc = CanEncoder(board_id=2, fd=fd, sync_us=5000, n_channels=n_channels)
    out: list[tuple[int, CanFrame, np.ndarray | None]] = []
    sent = 0
    for c, ev in enumerate(spikes(seed, n_channels=n_channels)):
        i = 0
        for f in enc.events(ev, (c + 1) * 1000):
            cls = f.arbitration_id >> 4
            if cls in CAN_EVENT_CLASSES:
                n = events_in_frame(f, fd)
                out.append((cls, f, ev[i:i + n]))
                i += n
            else:
                out.append((cls, f, None))
        sent += len(ev)
        if (c + 1) % STATUS_EVERY == 0:
            status = Status((c + 1) * 1000, sent, sent, 0, 0, 0, 0, True)
            out += [(4, f, None) for f in enc.status(status)]
    return out


@pytest.mark.parametrize("n_channels", CHANNELS)
@pytest.mark.parametrize("fd", [False, True])
@SETTINGS
@given(seed=st.integers(0, 10_000), drops=st.sets(st.integers(0, 10_000), max_size=12),
       dups=st.sets(st.integers(0, 10_000), max_size=6),
       foreign=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 0x7FF),
                                  st.binary(max_size=8)), max_size=6),
       batch=st.integers(1, 50))
def test_can_lost_duplicated_foreign_frames(n_channels: int, fd: bool, seed: int,
                                            drops: set[int], dups: set[int], foreign: list,
                                            batch: int) -> None:
    frames = can_frames(seed, fd, n_channels)
    top = 7 if n_channels > 338 else 6  # the board's highest frame class
    n_status = 1 if fd else 8
    last_ok = len(frames) - n_status - 2  # the first frame and the final status survive
    drop = set()
    for d in sorted(1 + x % last_ok for x in drops):
        if d - 1 not in drop and d + 1 not in drop:  # single losses: every gap is seen
            drop.add(d)
    dup = {d % len(frames) for d in dups} - drop
    extra = {w % len(frames): (ident, data) for w, ident, data in foreign  # no class of board 2
             if (ident & 0xF) != 2 or not (1 <= ident >> 4 <= top
                                           or ident >> 4 in CLASS_OF_KIND.values())}
    stream: list[CanFrame] = []
    for i, (_, f, _) in enumerate(frames):
        if i in extra:
            stream.append(CanFrame(extra[i][0], extra[i][1], fd))
        if i in drop:
            continue
        stream.append(f)
        if i in dup:
            stream.append(f)
    dec = CanDecoder(board_id=2, fd=fd)
    got, records = [], []
    for k in range(0, len(stream), batch):
        res = dec.feed(stream[k:k + batch])
        got.append(res.events)
        records += res.records
    expected, sync_ok, lost, base_seen = [], False, 0, False
    group: list[int] = []
    for i, (cls, _, ev) in enumerate(frames):
        ok = i not in drop
        if cls == 3:
            sync_ok = ok
        elif cls in CAN_EVENT_CLASSES:
            assert ev is not None
            if ok and sync_ok:
                expected.append(ev)
            elif base_seen:
                lost += len(ev)
        elif cls == 4:
            group.append(i)
            if len(group) == n_status:
                if not base_seen and not any(g in drop for g in group):
                    base_seen = True
                group = []
    c = dec.counters
    np.testing.assert_array_equal(np.concatenate(got), np.concatenate(expected))
    assert c.frames_lost == len(drop)
    assert c.duplicates == len(dup)
    assert c.frames_ok == len(frames) - len(drop)
    assert c.foreign_frames == len(extra)
    assert c.events_lost == lost
    assert records, "the final status must be decoded"


@pytest.mark.parametrize("fd", [False, True])
@SETTINGS
@given(frames=st.lists(st.tuples(st.integers(-5, 0x900), st.binary(max_size=64)),
                       max_size=200))
def test_can_random_frames_never_raise(fd: bool, frames: list[tuple[int, bytes]]) -> None:
    dec = CanDecoder(board_id=0, fd=fd)
    res = dec.feed(CanFrame(i, d, fd) for i, d in frames)
    assert len(res.events) == dec.counters.events_decoded
    assert dec.counters.frames_ok + dec.counters.malformed + dec.counters.foreign_frames + \
        dec.counters.duplicates == len(frames)


def _genibus(data: bytes) -> int:
    """CRC-16/GENIBUS written from its definition (SPEC.md §2), independent of the codec."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1) & 0xFFFF
    return crc ^ 0xFFFF


def _every_packet_type() -> list[bytes]:
    """One real packet of each serial type (SYNC, EVENTS with words and a bitmap, WIDE_EVENTS,
    STATUS, MARKER, COMMAND, ACK), each with its delimiter."""
    from protocol_examples import ACK, BURST, COMMAND, EVENTS, MARKER, STATUS, WIDE_EVENTS

    stream = SerialEncoder().events(EVENTS, 1000) + SerialEncoder().events(BURST, 1000)
    stream += SerialEncoder(n_channels=15_730).events(WIDE_EVENTS, 1000)
    enc = SerialEncoder()
    stream += enc.status(STATUS) + enc.marker(MARKER) + enc.command(COMMAND) + enc.ack(ACK)
    long_ev = spikes(3, rate_per_ms=400.0)[0]  # a long events packet (about 400 events)
    stream += SerialEncoder().events(long_ev, 1000)
    return [p + b"\x00" for p in stream.split(b"\x00") if p]


def test_crc_is_crc16_genibus() -> None:
    assert _genibus(b"123456789") == 0xD64E
    for packet in _every_packet_type():
        body = bytearray()
        raw = packet[:-1]
        i = 0
        while i < len(raw):  # COBS decode (SPEC.md §2)
            code = raw[i]
            body += raw[i + 1:i + code]
            i += code
            if code < 255 and i < len(raw):
                body.append(0)
        assert _genibus(bytes(body[:-2])) == int.from_bytes(body[-2:], "big")


def test_appended_zeros_never_pass_the_crc() -> None:
    """``0x01`` bytes inserted before a packet's delimiter decode to appended zero bytes: for
    every packet type and every count that keeps the packet within 1032 bytes, the packet is
    refused (a CRC error), no event is added, and the next packet decodes."""
    packets = _every_packet_type()
    for packet in packets:
        ok = SerialDecoder()
        ok.feed(packet)
        assert ok.counters.frames_ok == 1 and ok.counters.crc_errors == 0
        for k in range(1, 1033 - len(packet) + 1):
            dec = SerialDecoder()
            bad = packet[:-1] + b"\x01" * k + b"\x00"
            got = dec.feed(bad)
            assert len(got.events) == 0 and got.records == [], (packet.hex(), k)
            assert dec.counters.frames_ok == 0 and dec.counters.crc_errors == 1, (packet, k)
            dec.feed(packet)
            assert dec.counters.frames_ok == 1, (packet.hex(), k)


def test_linear_suffix_check_matches_decoding_each_suffix() -> None:
    """The one-pass suffix check (framing.suffix_checks) marks exactly the starts whose suffix
    COBS-decodes to at least 4 bytes with a good CRC, on damaged real packets and junk."""
    from protocols.framing import CRC_RESIDUE, cobs_decode, crc16, suffix_checks

    rng = np.random.default_rng(5)
    stream = b"".join(_every_packet_type())
    pieces = [p for p in stream.split(b"\x00") if p]
    cases = [rng.integers(1, 256, int(rng.integers(1, 1032)), dtype=np.uint8).tobytes()
             for _ in range(40)]
    for _ in range(200):  # a damaged packet run into the next (a lost delimiter) and more
        i = int(rng.integers(0, len(pieces) - 1))
        junk = rng.integers(1, 256, int(rng.integers(0, 30)), dtype=np.uint8).tobytes()
        cases.append((junk + pieces[i] + b"\x01" * int(rng.integers(0, 3)) + pieces[i + 1])
                     [-1032:])
    hits = 0
    for case in cases:
        buf = np.frombuffer(case, dtype=np.uint8)
        n = len(case)
        scratch = [np.empty(n + 1, dtype=np.int64) for _ in range(3)]
        passes = np.empty(n + 1, dtype=np.bool_)
        suffix_checks(buf, 0, n, *scratch, passes)
        dec = np.empty(n + 8, dtype=np.uint8)
        for k in range(n):
            m = cobs_decode(buf, k, n, dec)
            want = m >= 4 and crc16(dec, 0, m) == CRC_RESIDUE
            assert bool(passes[k]) == want, (case.hex(), k)
            hits += want
    assert hits >= 200  # the packet after each lost delimiter is found
