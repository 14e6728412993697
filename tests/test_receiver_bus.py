"""Several boards on one link decoded at once. CAN: three emulated boards (ids 0, 5, 9) and a
fourth the receiver does not listen to (id 3) share a python-can virtual bus (classic and
FD), and a real vcan0 (CAN FD; inside user-mode Linux where the host has none); UDP: three
boards send to one port of 127.0.0.1. Each board's counters are exact, the foreign board's
frames are counted, the combined view is the sum."""

from __future__ import annotations

import math
import random
import threading
import time

import pytest

from firmware_sim.board import Board, BoardConfig
from skinhil.receiver import WindowDecoder
from skinhil.receiver.bus import BusReceiver
from skinhil.receiver.training import train_decoder
from skinhil.transports import CanTransport, Transport, UdpTransport

BOARD_IDS = (0, 5, 9)
OTHER_ID = 3
DURATION_S = 1.5
VCAN_DURATION_S = 0.5
"""Through vcan0 (inside user-mode Linux, where four boards' threads and the receiver share one
slow CPU: 0.5 s of board time took 6.6 s of wall time, 1.5 s about 90 s)."""


@pytest.fixture(scope="module")
def small_decoder() -> WindowDecoder:
    """A decoder trained without noise on 9 stimuli (the bus test scores nothing)."""
    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False)
    return WindowDecoder(decoder)


@pytest.mark.parametrize("kind", ["can", "canfd", "udp",
                                  pytest.param("vcan-fd", marks=pytest.mark.vcan)])
def test_three_boards_on_one_link_each_exact(small_decoder: WindowDecoder, kind: str) -> None:
    chan, interface = (("vcan0", "socketcan") if kind.startswith("vcan")
                       else (f"bus-{random.getrandbits(32)}", "virtual"))
    fd = kind.endswith("fd")
    host: Transport = UdpTransport("127.0.0.1", 0, listen=True) if kind == "udp" else \
        CanTransport(chan, interface, fd=fd)

    def open_link() -> Transport:
        if kind == "udp":
            return UdpTransport("127.0.0.1", host.port)  # type: ignore[attr-defined]
        return CanTransport(chan, interface, fd=fd)

    ids = BOARD_IDS if kind == "udp" else (*BOARD_IDS, OTHER_ID)
    boards = {b: Board(BoardConfig(board_id=b, seed=b, rest_s=0.05), open_link) for b in ids}
    bus = BusReceiver(host, small_decoder, () if kind == "udp" else BOARD_IDS)
    key = {b: f"127.0.0.1:{boards[b].link.transport.port}" if kind == "udp" else b  # type: ignore[union-attr]
           for b in BOARD_IDS}
    summaries = {}
    threads = [threading.Thread(target=lambda b=b: summaries.__setitem__(
        b, boards[b].run(VCAN_DURATION_S if kind.startswith("vcan") else DURATION_S)))
        for b in boards]
    for t in threads:
        t.start()
    quiet_since = None
    while quiet_since is None or time.monotonic() - quiet_since < 0.5:
        parts = bus.receive(0.02)
        bus.feed(parts)
        if parts or any(t.is_alive() for t in threads):
            quiet_since = None
        elif quiet_since is None:
            quiet_since = time.monotonic()
    bus.flush()
    bus.transport.shutdown()
    reports = bus.link_reports()
    assert set(reports) == set(key.values())
    for b in BOARD_IDS:
        s, r, rx = summaries[b], reports[key[b]], bus.boards[key[b]]
        assert s.sent == s.generated > 0 and s.dropped == 0
        assert r.events_decoded == s.sent
        assert rx.last_status.events_generated == s.generated
        assert r.frames_lost == r.lost_on_link == r.untimed_events == r.malformed == 0
        assert rx.codec.counters.foreign_frames == 0
    if kind != "udp":
        assert bus.foreign_frames == summaries[OTHER_ID].units_sent > 0
    combined = bus.combined_report()
    assert combined.events_decoded == sum(summaries[b].sent for b in BOARD_IDS)
    assert combined.frames_ok == sum(r.frames_ok for r in reports.values())


def test_udp_sources_are_capped_and_filtered(small_decoder: WindowDecoder) -> None:
    """Past ``max_sources`` a new UDP source is refused and its datagrams counted, and with an
    allow-list only the listed sources become boards: six senders over real loopback."""
    import socket as socket_module

    senders = [socket_module.socket(socket_module.AF_INET, socket_module.SOCK_DGRAM)
               for _ in range(6)]
    host = UdpTransport("127.0.0.1", 0, listen=True)
    try:
        for s in senders:
            s.bind(("127.0.0.1", 0))
        names = [f"127.0.0.1:{s.getsockname()[1]}" for s in senders]
        for cap, allow, want in ((3, None, names[:3]), (16, [names[4], "10.0.0.1"],
                                                        [names[4]])):
            bus = BusReceiver(host, small_decoder, max_sources=cap, allow=allow)
            for _ in range(2):
                for s in senders:
                    s.sendto(b"\x01", ("127.0.0.1", host.port))
                    time.sleep(0.002)  # in order: the first three are heard first
                got: dict = {}
                end = time.monotonic() + 5
                while sum(1 for _ in got) < len(want) and time.monotonic() < end:
                    parts = bus.receive(0.05)
                    bus.feed(parts)
                    got.update(parts)
                time.sleep(0.05)
                bus.feed(bus.receive(0.05))
            assert sorted(bus.boards) == sorted(want), (cap, allow)
            assert bus.refused_datagrams == 2 * (6 - len(want))
    finally:
        host.shutdown()
        for s in senders:
            s.close()


def test_drain_decodes_what_the_link_already_received(small_decoder: WindowDecoder,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Datagrams already in the socket when a receiver stops (listen on Ctrl-C) are decoded
    by ``drain()``: the totals count every event sent, none left in the kernel's queue."""
    import numpy as np

    import skinhil.transports.udp as udp

    monkeypatch.setattr(udp, "RECV_BATCH", 16)  # one read takes 16 datagrams of the 200

    import protocols
    from skinhil.events import make_events
    from skinhil.receiver import Receiver

    host = UdpTransport("127.0.0.1", 0, listen=True)
    board = UdpTransport("127.0.0.1", host.port)
    try:
        enc = protocols.SerialEncoder()
        sent = 0
        for ms in range(200):
            ev = make_events(np.arange(5, dtype=np.int64) * 100 + ms * 1000, np.arange(5) * 7)
            board.send(enc.events(ev, (ms + 1) * 1000))
            sent += len(ev)
        time.sleep(0.2)
        rx = Receiver(host, small_decoder)
        rx.poll(0.0)  # one read: a batch, not everything
        first = rx.link_report().events_decoded
        rx.drain()
        assert first < sent and rx.link_report().events_decoded == sent
        bus = BusReceiver(host, small_decoder)
        for ms in range(200, 300):
            ev = make_events(np.arange(5, dtype=np.int64) * 100 + ms * 1000, np.arange(5) * 7)
            board.send(enc.events(ev, (ms + 1) * 1000))
        time.sleep(0.2)
        bus.drain()
        assert bus.combined_report().events_decoded == 500
    finally:
        board.shutdown()
        host.shutdown()


def test_receiver_takes_the_session_and_stops_at_the_run_end(
        small_decoder: WindowDecoder) -> None:
    """One board's receiver: the SESSION and its table are kept (a new SESSION starts the
    table again), a SESSION of another channel count is reported, and RUN_END ends run()."""
    from protocol_examples import RUN_END, SESSION, TABLE

    import protocols
    from skinhil.receiver import Receiver, ReceiverListener

    class Heard(ReceiverListener):
        def __init__(self) -> None:
            self.items: list[object] = []

        def on_session(self, session: object) -> None:
            self.items.append(session)

        def on_run_end(self, run_end: object) -> None:
            self.items.append(run_end)

        def on_link_error(self, message: str) -> None:
            self.items.append(message)

    heard = Heard()
    rx = Receiver(UdpTransport("127.0.0.1", 0, listen=True), small_decoder, listeners=[heard])
    try:
        enc = protocols.SerialEncoder()
        other = protocols.Session(**{**vars(SESSION), "n_channels": 100, "n_stimuli": 1})
        rx.feed(b"".join(enc.session_record(r) for r in (other, TABLE[1], SESSION, *TABLE)))
        assert rx.session == SESSION and rx.stimuli == {0: "0deg_0.1N", 10: "A"}
        assert "decoder expects 338 channels but the stream has 100" in str(heard.items[0])
        assert heard.items[1:] == [other, SESSION]
        rx.feed(enc.session_record(RUN_END))
        assert rx.run_end == RUN_END and rx.run_ends == 1 and heard.items[-1] == RUN_END
        t0 = time.monotonic()
        rx.run(duration_s=5.0)  # returns at once: the board finished
        assert time.monotonic() - t0 < 1.0
    finally:
        rx.transport.shutdown()
