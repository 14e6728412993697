"""Every compiled codec kernel fed inputs longer than its buffers, run in a bounds-checked
build (``NUMBA_BOUNDSCHECK=1``, a fresh ``NUMBA_CACHE_DIR``): a store out of bounds raises
IndexError there instead of corrupting memory. Run as ``python -m harness.bounds_fuzz``
(from ``tests/``); prints ``ok`` and the number of cases, or fails with the traceback.

Covered: the serial framing (``frame_into``, ``cobs_decode``, ``suffix_checks`` through the
decoder), the serial and CAN encoders and decoders of both wire versions
(``serial_kernels``, ``can_kernels``, ``event_input``), the replay's re-framing
(``protocols.resequence``) and the model's spike scan (``raster_to_events``).
"""

from __future__ import annotations

import os

import numba
import numpy as np

import protocols
from protocols import resequence
from protocols import serial_kernels as sk
from protocols.events import make_events
from protocols.framing import cobs_decode, frame_into
from skinhil.model.neurons import raster_to_events

SEED = 32


def _dense_events(rng: np.random.Generator, n_channels: int, n_ms: int) -> np.ndarray:
    """Every channel spiking in most steps: far more events than a packet or frame holds."""
    steps = n_ms * 10
    raster = rng.random((steps, n_channels)) < 0.7
    return raster_to_events(raster, 1e-4)


def _serial(rng: np.random.Generator) -> int:
    cases = 0
    for n_channels in (338, 4000):
        enc = protocols.SerialEncoder(n_channels=n_channels)
        ev = _dense_events(rng, n_channels, 3)
        wire = enc.events(ev, 3_000)
        cases += 1
        for max_packets in (1, 2):
            ev2 = _dense_events(rng, n_channels, 2)
            enc2 = protocols.SerialEncoder(n_channels=n_channels)
            enc2.events_upto(ev2, 2_000, max_packets)
            cases += 1
        dec = protocols.SerialDecoder()
        got = dec.feed(wire)
        assert got.events.shape[0] == ev.shape[0]
        # runs without a delimiter, of COBS codes and of garbage, longer than MAX_WIRE
        for n in (sk.MAX_WIRE - 1, sk.MAX_WIRE + 1, 2_295, 3 * sk.MAX_WIRE, 20_000):
            for run in (bytes([255] + [7] * 254) * (n // 255 + 1),
                        rng.integers(1, 256, n, dtype=np.uint8).tobytes()):
                for tail in (b"", b"\x00"):
                    protocols.SerialDecoder().feed(run[:n] + tail + wire[:500])
                    d = protocols.SerialDecoder()
                    for k in range(0, n, 997):
                        d.feed(run[k:k + 997])
                    d.feed(tail + wire)
                    cases += 2
        # damaged real streams in random chunks
        for _ in range(40):
            b = bytearray(wire)
            for _ in range(int(rng.integers(1, 30))):
                b[int(rng.integers(0, len(b)))] = int(rng.integers(0, 256))
            d = protocols.SerialDecoder()
            pos = 0
            while pos < len(b):
                step = int(rng.integers(1, 5_000))
                d.feed(bytes(b[pos:pos + step]))
                pos += step
            cases += 1
    return cases


def _framing(rng: np.random.Generator) -> int:
    cases = 0
    for n in (0, 1, 253, 254, 255, 1024, 3000):
        body = np.empty(n + 2, dtype=np.uint8)
        body[:n] = rng.integers(0, 256, n, dtype=np.uint8)
        m = n + 2
        out = np.empty(m + m // 254 + 2, dtype=np.uint8)  # the documented room, exactly
        end = frame_into(body, n, out, 0)
        dec = np.empty(end, dtype=np.uint8)  # a COBS decode is never longer than its input
        assert cobs_decode(out, 0, end - 1, dec) == m
        cases += 1
    return cases


def _resequence(rng: np.random.Generator) -> int:
    cases = 0
    enc = protocols.SerialEncoder()
    packet = enc.events(_dense_events(rng, 338, 1), 1_000).split(b"\0")[1] + b"\0"
    assert resequence.serial_packet_seq(packet) is not None
    for n in (1, 4, 254, 255, 1030, sk.MAX_WIRE, sk.MAX_WIRE + 1, 2_064, 2_295, 5_000, 70_000):
        for run in (bytes([255] + [7] * 254) * (n // 255 + 1),
                    rng.integers(1, 256, n, dtype=np.uint8).tobytes()):
            crafted = run[:n] + b"\0"
            resequence.serial_packet_seq(crafted)
            resequence.serial_packet_with_seq(crafted, 5)
            cases += 1
    for seq in range(0, 600, 7):
        assert resequence.serial_packet_seq(
            resequence.serial_packet_with_seq(packet, seq)) == seq % 256
        cases += 1
    return cases


def _can(rng: np.random.Generator) -> int:
    cases = 0
    for fd in (False, True):
        for n_channels in (338, 4000):
            enc = protocols.CanEncoder(fd=fd, n_channels=n_channels)
            ev = _dense_events(rng, n_channels, 2)
            frames = enc.events(ev, 2_000)
            enc2 = protocols.CanEncoder(fd=fd, n_channels=n_channels)
            enc2.events_upto(_dense_events(rng, n_channels, 2), 2_000, 1)
            got = protocols.CanDecoder(fd=fd).feed(frames)
            assert got.events.shape[0] == ev.shape[0]
            cases += 2
            # frames of every id and length, garbage data, mixed with real ones
            width = 64 if fd else 8
            junk = [protocols.CanFrame(int(rng.integers(0, 0x800)),
                                       rng.integers(0, 256, int(rng.integers(0, width + 1)),
                                                    dtype=np.uint8).tobytes(), fd)
                    for _ in range(3_000)]
            mixed = junk[:1_500] + frames + junk[1_500:]
            protocols.CanDecoder(fd=fd).feed(mixed)
            for k in range(0, len(mixed), 333):
                protocols.CanDecoder(fd=fd).feed(mixed[k:k + 333])
            for frame in junk[:200]:
                resequence.can_frame_with_seq(frame, int(rng.integers(0, 1000)))
            cases += 3
    return cases


def _raster(rng: np.random.Generator) -> int:
    cases = 0
    for shape in ((1, 1), (3, 63), (5, 64), (7, 65), (10, 338), (2, 17_866), (40, 1000)):
        for p in (0.0, 0.01, 1.0):
            r = rng.random(shape) < p
            ev = raster_to_events(r, 1e-4)
            assert ev.shape[0] == int(r.sum())
            cases += 1
    return cases


def main() -> None:
    """Run every case; ``ok <cases>`` on success."""
    if not numba.config.BOUNDSCHECK:
        raise SystemExit("run with NUMBA_BOUNDSCHECK=1 (and a fresh NUMBA_CACHE_DIR)")
    rng = np.random.default_rng(SEED)
    cases = _framing(rng) + _resequence(rng) + _serial(rng) + _can(rng) + _raster(rng)
    assert make_events(np.zeros(0, np.int64), np.zeros(0, np.uint16)).shape[0] == 0
    print("ok", cases, os.environ.get("NUMBA_CACHE_DIR", ""))


if __name__ == "__main__":
    main()
