"""Seeded fuzzing of the decoders over real captures of every packet and frame type (serial,
as on a UART, a pty or UDP datagrams; classic CAN; CAN FD), bounded to well under a minute.

Each case mutates a clean capture (bit flips, bursts, inserted, dropped, duplicated and
reordered bytes or frames, truncation, garbage, ``0x01`` runs before delimiters), decodes it
in random chunks and checks: no exception escapes; a damaged unit moves a counter; no event
decoded that the board did not send, except within the CRC-16 bound (2^-16 per candidate
check, further cut by the layout checks); none at all from inserted ``0x01`` bytes; and
decoding recovers: a clean tail after the damage decodes whole.

Each run draws :data:`CASES` cases from a seed of its own (:data:`RUN_SEED`, named in every
failure; ``SKINHIL_FUZZ_SEED=N`` replays one), so the cases covered grow with every CI run
while one run stays short."""

from __future__ import annotations

import os
import secrets

import numpy as np
from protocol_examples import distinct_events

from protocols import (
    Ack,
    CanDecoder,
    CanEncoder,
    CanFrame,
    CommandCode,
    Marker,
    MarkerPhase,
    SerialDecoder,
    SerialEncoder,
    Status,
)

SEED = 16
CASES = 200
RUN_SEED = int(os.environ.get("SKINHIL_FUZZ_SEED", secrets.randbelow(2**31)))
"""This run's seed, beside each test's own (``SEED``, ``SEED + 1``, ...)."""
STATUS = Status(t_us=0, events_generated=0, events_sent=0, events_dropped=0, events_queued=0,
                late_ticks=0, rx_errors=0, running=True)


def _calls(rng: np.random.Generator, n_channels: int, t0_ms: int, n_ms: int) -> list:
    calls = []
    for ms in range(t0_ms, t0_ms + n_ms):
        n = int(rng.poisson(20 if rng.random() < 0.8 else 400))  # a few crowded (bitmap) ms
        t = rng.integers(0, 10, n) * 100 + ms * 1000
        calls.append((distinct_events(t, rng.integers(0, n_channels, n)), (ms + 1) * 1000))
    return calls


def _capture(enc, rng: np.random.Generator, n_channels: int, t0_ms: int, n_ms: int):
    """Units (packets or frames) of ``n_ms`` ms of events with statuses, markers and ACKs
    between them; and the events they carry."""
    units: list = []
    events = []
    for i, (ev, t_end) in enumerate(_calls(rng, n_channels, t0_ms, n_ms)):
        out = enc.events(ev, t_end)
        units += [p + b"\x00" for p in out.split(b"\x00") if p] if isinstance(out, bytes) \
            else list(out)
        events.append(ev)
        extra = (enc.status(STATUS) if i % 3 == 0 else
                 enc.marker(Marker(t_end, i, MarkerPhase(i % 2))) if i % 3 == 1 else
                 enc.ack(Ack(i, CommandCode.PING, True)))
        units += [extra] if isinstance(extra, bytes) else list(extra)
    return units, np.concatenate(events)


def _pairs(ev: np.ndarray) -> set[tuple[int, int]]:
    return set(zip(ev["t"].tolist(), ev["addr"].tolist(), strict=True))


def _mutate_bytes(rng: np.random.Generator, data: bytes) -> bytes:
    b = bytearray(data)
    kind = int(rng.integers(0, 8))
    pos = int(rng.integers(0, len(b)))
    if kind == 0:  # bit flips
        for _ in range(int(rng.integers(1, 4))):
            b[int(rng.integers(0, len(b)))] ^= 1 << int(rng.integers(0, 8))
    elif kind == 1:  # a burst
        n = int(rng.integers(1, 64))
        b[pos:pos + n] = rng.integers(0, 256, len(b[pos:pos + n]), dtype=np.uint8).tobytes()
    elif kind == 2:  # inserted garbage
        b[pos:pos] = rng.integers(0, 256, int(rng.integers(1, 2000)), dtype=np.uint8).tobytes()
    elif kind == 3:  # dropped bytes
        del b[pos:pos + int(rng.integers(1, 300))]
    elif kind == 4:  # a duplicated span
        n = int(rng.integers(1, 500))
        b[pos:pos] = b[pos:pos + n]
    elif kind == 5:  # two spans swapped
        q = int(rng.integers(0, len(b)))
        lo, hi = sorted((pos, q))
        n = min(int(rng.integers(1, 200)), hi - lo)
        b[lo:hi + n] = b[hi:hi + n] + b[lo + n:hi] + b[lo:lo + n]
    elif kind == 6:  # truncation
        del b[pos:]
    else:  # a long non-zero run
        b[pos:pos] = bytes([int(rng.integers(1, 256))]) * int(rng.integers(1, 3000))
    return bytes(b)


def test_serial_fuzz() -> None:
    rng = np.random.default_rng((SEED, RUN_SEED))
    phantoms = candidates = 0
    for case in range(CASES):
        n_channels = 338 if case % 3 else 15_730
        enc = SerialEncoder(n_channels=n_channels)
        units, sent = _capture(enc, rng, n_channels, 0, 40)
        tail_units, tail = _capture(enc, rng, n_channels, 200, 20)
        clean = b"".join(units)
        bad = _mutate_bytes(rng, clean)
        stream = bad + b"\x00" + b"".join(tail_units)  # the tail starts with a SYNC
        dec = SerialDecoder()
        got = []
        i = 0
        while i < len(stream):  # random chunks, as reads arrive
            n = int(rng.integers(1, 4000))
            got.append(dec.feed(stream[i:i + n]).events)
            i += n
        ev = np.concatenate(got)
        c = dec.counters
        extra = _pairs(ev) - _pairs(sent) - _pairs(tail)
        phantoms += len(extra)
        candidates += c.crc_errors + c.malformed
        if bad != clean:
            moved = (c.crc_errors + c.malformed + c.duplicates + c.frames_lost
                     + c.bytes_discarded + c.events_untimed)
            assert moved > 0 or _pairs(ev) >= _pairs(sent), (RUN_SEED, case)
        assert _pairs(tail) <= _pairs(ev), \
            f"SKINHIL_FUZZ_SEED={RUN_SEED} case {case}: no recovery after the damage"
    # the CRC-16 bound: at most one candidate in 2^16 passes by chance, each adding at most
    # the events of one packet (340); the layout checks refuse most of those too
    assert phantoms <= 340 * (candidates * 1032 / 65536 + 1), (RUN_SEED, phantoms, candidates)


def test_serial_fuzz_zero_insertion_adds_nothing() -> None:
    """``0x01`` bytes inserted before any delimiter of a real capture add no event."""
    rng = np.random.default_rng((SEED + 1, RUN_SEED))
    for case in range(200):
        n_channels = 338 if case % 2 else 15_730
        units, sent = _capture(SerialEncoder(n_channels=n_channels), rng, n_channels, 0, 20)
        k = int(rng.integers(0, len(units)))
        units[k] = units[k][:-1] + b"\x01" * int(rng.integers(1, 9)) + b"\x00"
        dec = SerialDecoder()
        ev = dec.feed(b"".join(units)).events
        assert _pairs(ev) <= _pairs(sent), (RUN_SEED, case)
        assert dec.counters.crc_errors + dec.counters.malformed >= 1, (RUN_SEED, case)


def test_can_fuzz() -> None:
    rng = np.random.default_rng((SEED + 2, RUN_SEED))
    for case in range(CASES):
        fd = bool(case % 2)
        n_channels = 338 if case % 3 else 15_730
        enc = CanEncoder(board_id=3, fd=fd, n_channels=n_channels)
        units, sent = _capture(enc, rng, n_channels, 0, 30)
        frames = list(units)
        kind = int(rng.integers(0, 6))
        k = int(rng.integers(0, len(frames)))
        f = frames[k]
        if kind == 0:  # bit flips in one frame's data (as if the bus CRC missed them)
            data = bytearray(f.data)
            data[int(rng.integers(0, len(data)))] ^= 1 << int(rng.integers(0, 8))
            frames[k] = CanFrame(f.arbitration_id, bytes(data), f.is_fd)
        elif kind == 1:  # a wrong length
            n = int(rng.integers(0, 65 if fd else 9))
            frames[k] = CanFrame(f.arbitration_id, (bytes(f.data) + bytes(64))[:n], f.is_fd)
        elif kind == 2:  # dropped frames
            del frames[k:k + int(rng.integers(1, 40))]
        elif kind == 3:  # a duplicate, immediate or late
            frames.insert(min(len(frames), k + int(rng.integers(1, 20))), f)
        elif kind == 4:  # two frames swapped
            q = int(rng.integers(0, len(frames)))
            frames[k], frames[q] = frames[q], frames[k]
        else:  # garbage frames on the board's IDs
            for _ in range(int(rng.integers(1, 20))):
                n = 64 if fd else 8
                frames.insert(k, CanFrame(0x30 + (int(rng.integers(1, 8)) << 4) - 0x30 + 3,
                                          rng.integers(0, 256, n, dtype=np.uint8).tobytes(),
                                          fd))
        # a tail of 150 ms: a SYNC every 50 ms; a garbage frame may leave the first one a
        # (4-bit) duplicate, so recovery is judged on the events after 260 ms
        tail_units, tail = _capture(enc, rng, n_channels, 200, 150)
        tail = tail[tail["t"] >= 260_000]
        dec = CanDecoder(board_id=3, fd=fd)
        got = []
        stream = frames + tail_units  # the tail starts with a SYNC
        i = 0
        while i < len(stream):
            n = int(rng.integers(1, 50))
            got.append(dec.feed(stream[i:i + n]).events)
            i += n
        ev = np.concatenate(got)
        assert _pairs(tail) <= _pairs(ev), \
            f"SKINHIL_FUZZ_SEED={RUN_SEED} case {case}: no recovery after the damage"
