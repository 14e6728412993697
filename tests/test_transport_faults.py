"""The fault-injection wrapper on a real pty: it injects what it says, and counts it exactly."""

from __future__ import annotations

import os

import numpy as np
import pytest

from skinhil.errors import ConfigError
from skinhil.transports import FaultParams, FaultyTransport, PtyMasterTransport, SerialTransport


def _pump(params: FaultParams, data: bytes) -> tuple[bytes, FaultyTransport]:
    master, slave_fd = PtyMasterTransport.open_pair()
    faulty = FaultyTransport(master, params)
    board = SerialTransport(master.slave_path)
    got = bytearray()
    try:
        for i in range(0, len(data), 512):
            board.send(data[i:i + 512], timeout=1.0)
            got += faulty.recv(0.05)
        while True:
            chunk = faulty.recv(0.1)
            if not chunk:
                break
            got += chunk
    finally:
        board.shutdown()
        faulty.shutdown()
        os.close(slave_fd)
    return bytes(got), faulty


def test_byte_corruption_is_counted_exactly():
    data = np.random.default_rng(0).integers(0, 256, 20000, dtype=np.uint8).tobytes()
    got, faulty = _pump(FaultParams(corrupt_byte_p=0.01, seed=3, serial_unit="chunk"), data)
    assert len(got) == len(data)
    diff = int(np.count_nonzero(np.frombuffer(got, np.uint8) != np.frombuffer(data, np.uint8)))
    assert diff == faulty.injected.bytes_corrupted > 100


def test_dropped_and_duplicated_chunks_are_counted():
    data = bytes(range(256)) * 80
    got, faulty = _pump(FaultParams(drop_p=0.1, duplicate_p=0.1, seed=5, serial_unit="chunk"), data)
    inj = faulty.injected
    assert inj.units_dropped > 0 and inj.units_duplicated > 0
    assert len(got) >= len(data) - inj.bytes_dropped
    assert inj.units_seen >= inj.units_dropped + inj.units_duplicated


def test_delay_keeps_order():
    data = bytes(range(256)) * 20
    got, faulty = _pump(FaultParams(delay_p=0.5, delay_s=0.02, seed=1, serial_unit="chunk"), data)
    assert got == data and faulty.injected.units_delayed > 0


def test_packet_mode_drops_and_damages_whole_packets_only():
    rng = np.random.default_rng(4)
    packets = [bytes(rng.integers(1, 256, int(rng.integers(3, 40)), dtype=np.uint8)) + b"\0"
               for _ in range(2000)]
    got, faulty = _pump(FaultParams(drop_p=0.02, corrupt_byte_p=0.01, seed=6), b"".join(packets))
    inj = faulty.injected
    assert inj.units_seen == len(packets)
    out = got.split(b"\0")[:-1]
    # delimiters are never hit (a byte flipped to zero may split a damaged packet)
    assert len(out) >= len(packets) - inj.units_dropped
    sent = {p[:-1] for p in packets}
    intact = sum(1 for p in out if p in sent)
    assert intact == len(packets) - inj.units_dropped - inj.corrupted_units
    assert inj.corrupted_units > 0 and inj.units_dropped > 0


@pytest.mark.parametrize("bad", [{"drop_p": 1.5}, {"corrupt_byte_p": -0.1},
                                 {"delay_s": float("nan")}, {"serial_unit": "frame"}])
def test_bad_fault_parameters_are_refused(bad):
    with pytest.raises(ConfigError):
        FaultParams(**bad)
