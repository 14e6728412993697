"""One contract, every transport of :mod:`skinhil.transports`: loopback URL, pty pair, pty
master, the fault injector, python-can virtual bus, UDP on 127.0.0.1, vcan0 (classic and FD).

Each case gives a sending and a receiving :class:`skinhil.transports.Transport` (the
same object for ``loop://``). The pty case is a linked pair of real ptys made by socat; the
pty-master case writes the master end of ``os.openpty()`` and reads its slave with pyserial;
the faulty case is :class:`~skinhil.transports.FaultyTransport` with no fault configured around
a virtual bus (it must keep the contract of what it wraps); the vcan case two sockets on a real
``vcan0`` (inside user-mode Linux where the host has none).
"""

from __future__ import annotations

import random
import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import protocols
from skinhil.errors import TransportError
from skinhil.transports import (
    CanTransport,
    FaultParams,
    FaultyTransport,
    SerialTransport,
    Transport,
    open_link,
)

CASES = ["loop", "pty", "pty-master", "faulty", "virtual", "udp",
         pytest.param("vcan", marks=pytest.mark.vcan),
         pytest.param("vcan-fd", marks=pytest.mark.vcan)]


def _socat_pair(tmp: Path) -> tuple[subprocess.Popen[bytes], str, str]:
    socat = shutil.which("socat")
    if socat is None:
        pytest.fail("socat is needed for the linked pty pair: apt-get install -y socat")
    a, b = tmp / "ttyA", tmp / "ttyB"
    proc = subprocess.Popen([socat, f"pty,raw,echo=0,link={a}",
                             f"pty,raw,echo=0,link={b}"])
    end = time.monotonic() + 5
    while not (a.exists() and b.exists()):
        if time.monotonic() > end:
            proc.kill()
            pytest.fail("socat did not create the pty pair")
        time.sleep(0.01)
    return proc, str(a), str(b)


@pytest.fixture(params=CASES)
def link(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[tuple[Any, Any, str]]:
    kind = request.param
    proc = None
    if kind == "loop":
        tx = open_link("serial:loop://?baud=115200")
        rx = tx
    elif kind == "pty":
        proc, a, b = _socat_pair(tmp_path)
        tx, rx = SerialTransport(a, 921600), SerialTransport(b, 921600)
    elif kind == "pty-master":
        tx = open_link("pty:")
        rx = open_link(f"serial:{tx.slave_path}")
    elif kind == "udp":
        rx = open_link("udp:127.0.0.1:0", "host")
        tx = open_link(rx.url, "board")
    elif kind in ("virtual", "faulty"):
        chan = f"contract-{random.getrandbits(32)}"
        tx, rx = (open_link(f"can:{chan}?interface=virtual", role) for role in ("board", "host"))
        if kind == "faulty":
            tx = FaultyTransport(tx, FaultParams(seed=1), on_send=True, on_recv=False)
            rx = FaultyTransport(rx, FaultParams(seed=2))
    else:
        fd = kind == "vcan-fd"
        tx, rx = CanTransport("vcan0", fd=fd), CanTransport("vcan0", fd=fd)
    yield tx, rx, kind
    tx.shutdown()
    rx.shutdown()
    if proc is not None:
        proc.kill()
        proc.wait()


def _payloads(tx: Transport[Any], n: int) -> list[Any]:
    rng = random.Random(n)
    if not tx.carries_frames:
        return [bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 300))) for _ in range(n)]
    fd = tx.can_fd
    sizes = protocols.budget.CAN_FD_LENGTHS if fd else range(9)
    return [[protocols.CanFrame(rng.randrange(0x800), bytes(rng.getrandbits(8) for _ in
                                                            range(rng.choice(sizes))), fd)]
            for _ in range(n)]


def _collect(rx: Transport[Any], want: int, timeout_s: float) -> Any:
    got = rx.empty()
    end = time.monotonic() + timeout_s
    while len(got) < want and time.monotonic() < end:
        got += rx.recv(timeout=0.1)
    return got


def test_round_trip_in_order(link) -> None:
    tx, rx, kind = link
    payloads = _payloads(tx, 40 if kind.startswith("vcan") else 200)
    want = tx.empty()
    for p in payloads:
        want += p
    got: list[Any] = []
    reader = threading.Thread(target=lambda: got.append(_collect(rx, len(want), 10.0)))
    reader.start()
    for p in payloads:
        assert tx.send(p, timeout=1.0) == len(p)
    reader.join()
    assert got[0] == want


def test_burst_is_not_lost(link) -> None:
    """A burst larger than a socket's default buffer arrives whole (reader thread, SO_RCVBUF)."""
    tx, rx, kind = link
    n = 1500 if kind.startswith("vcan") else 3000
    if tx.kind != "can":
        frames = bytes(range(256)) * (n // 16)
        done = threading.Event()
        got: list[bytes] = []

        def read() -> None:
            got.append(_collect(rx, len(frames), 20.0))
            done.set()

        t = threading.Thread(target=read)
        t.start()
        assert tx.send(frames, timeout=20.0) == len(frames)
        t.join()
        assert got[0] == frames
        return
    batch = [protocols.CanFrame(0x100 + (i % 0x600), i.to_bytes(4, "little"), False)
             for i in range(n)]
    assert tx.send(batch, timeout=20.0) == n
    time.sleep(0.2)  # nobody calls recv meanwhile: the reader thread must keep up
    assert _collect(rx, n, 20.0) == batch


def test_timeouts_poll_deadline_and_block(link) -> None:
    tx, rx, kind = link
    t0 = time.monotonic()
    assert rx.recv(timeout=0) == rx.empty()
    assert time.monotonic() - t0 < 0.15  # a poll: well short of the 0.2 s deadline below
    t0 = time.monotonic()
    assert rx.recv(timeout=0.2) == rx.empty()
    assert 0.19 <= time.monotonic() - t0 < 1.5
    payload = _payloads(tx, 1)[0]
    threading.Timer(0.15, lambda: tx.send(payload, timeout=1.0)).start()
    t0 = time.monotonic()
    got = rx.recv(timeout=None)
    assert time.monotonic() - t0 >= 0.1
    got += _collect(rx, len(payload), 1.0) if len(got) < len(payload) else rx.empty()
    assert got == payload


def test_wire_time_and_shutdown(link) -> None:
    tx, rx, kind = link
    payload = _payloads(tx, 1)[0]
    link = getattr(tx, "inner", tx)  # the fault injector takes its wire time from its link
    if tx.kind == "serial":
        assert tx.wire_seconds(payload) == pytest.approx(len(payload) * 10 / link.baud)
    elif tx.kind == "udp":
        assert tx.wire_seconds(payload) == pytest.approx(len(payload) * 8 / link.bitrate)
    else:
        assert tx.wire_seconds(payload * 3) == pytest.approx(
            3 * protocols.can_frame_seconds(payload[0], link.bitrate, link.data_bitrate))
    with tx:
        pass
    tx.shutdown()  # idempotent
    with pytest.raises(TransportError, match="closed"):
        tx.send(payload, timeout=0.5)
    with pytest.raises(TransportError, match="closed"):
        tx.recv(timeout=0)


@pytest.mark.vcan
def test_a_forced_receive_overflow_shows_in_the_acks_lost() -> None:
    """A receiving socket that is not read overflows and drops frames by the hundred (whole
    periods of the classic 4-bit frame sequence); the ACK counter (SPEC.md §5.6) still
    counts every ACK it lost: received + lost = sent."""
    import can

    tx = CanTransport("vcan0")
    rx = can.Bus(interface="socketcan", channel="vcan0", receive_own_messages=False)
    rx.socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # overflows at once
    enc, dec = protocols.CanEncoder(), protocols.CanDecoder()
    acks_sent = 1
    try:
        def drain() -> list[protocols.CanFrame]:
            got = []
            while (msg := rx.recv(timeout=0.2)) is not None:
                got.append(protocols.CanFrame(msg.arbitration_id, bytes(msg.data),
                                              bool(msg.is_fd)))
            return got

        tx.send(enc.ack(protocols.Ack(998, protocols.CommandCode.PING, True)), timeout=2.0)
        before = drain()  # the receiver knows the counter before the overflow
        frames = []
        for k in range(60):  # an ACK among every ~20 frames of events
            ev = protocols.events.make_events(np.arange(40) * 100 + k * 10_000,
                                              np.arange(40) % 338)
            frames += enc.events(ev, (k + 1) * 10_000)
            frames += enc.ack(protocols.Ack(k, protocols.CommandCode.DECISION, True))
            acks_sent += 1
        for i in range(0, len(frames), 50):
            tx.send(frames[i:i + 50], timeout=2.0)
        first = drain()
        tx.send(enc.ack(protocols.Ack(999, protocols.CommandCode.PING, True)), timeout=2.0)
        acks_sent += 1
        result = dec.feed(before + first + drain())
    finally:
        rx.shutdown()
        tx.shutdown()
    acks = [r for r in result.records if isinstance(r, protocols.Ack)]
    assert len(first) < len(frames) // 2, "the socket did not overflow"
    assert acks[0].token == 998 and acks[-1].token == 999
    assert dec.counters.acks_lost > 0
    assert len(acks) + dec.counters.acks_lost == acks_sent
