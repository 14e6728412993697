"""What the UDP link adds to the transport contract (tests/test_transport_contract.py):
whole packets per datagram, several sources kept apart, no listener, address errors."""

from __future__ import annotations

import numpy as np
import pytest
from protocol_examples import distinct_events

import protocols
from skinhil.errors import TransportError
from skinhil.transports import UdpTransport
from skinhil.transports.udp import parse_address, split_packets


def _stream(n_events: int) -> bytes:
    enc = protocols.SerialEncoder()
    rng = np.random.default_rng(0)
    t = np.sort(rng.integers(0, 50_000, n_events)) * 100
    return enc.events(distinct_events(t, rng.integers(0, 338, n_events)), int(t[-1]) + 100)


def test_datagrams_hold_whole_packets_and_decode_alone() -> None:
    data = _stream(5000)
    grams = split_packets(data, 1472)
    assert b"".join(grams) == data and all(len(g) <= 1472 for g in grams)
    assert all(g.endswith(b"\0") for g in grams)
    total = 0
    for g in grams:  # each datagram decodes on its own (after the stream's first SYNC)
        dec = protocols.SerialDecoder()
        dec.feed(g)
        assert dec.counters.crc_errors == dec.counters.malformed == 0
        total += dec.counters.frames_ok
    whole = protocols.SerialDecoder()
    whole.feed(data)
    assert total == whole.counters.frames_ok and len(grams) > 1


def test_several_sources_are_kept_apart_and_commands_answer_the_last() -> None:
    with UdpTransport("127.0.0.1", 0, listen=True) as host:
        boards = [UdpTransport("127.0.0.1", host.port) for _ in range(3)]
        try:
            for i, b in enumerate(boards):
                assert b.send(bytes([i + 1, 0]), timeout=1.0) == 2
            got = []
            while len(got) < 3:
                got += host.recv_from(timeout=1.0)
            sources = {src: data for src, data in got}
            assert sorted(sources.values()) == [b"\x01\0", b"\x02\0", b"\x03\0"]
            assert {f"127.0.0.1:{b.port}" for b in boards} == set(sources)
            assert host.send(b"\x07\0", timeout=1.0) == 2
            last = next(b for b in boards if f"127.0.0.1:{b.port}" == got[-1][0])
            assert last.recv(timeout=1.0) == b"\x07\0"
        finally:
            for b in boards:
                b.shutdown()


def test_no_listener_loses_datagrams_without_failing() -> None:
    probe = UdpTransport("127.0.0.1", 0, listen=True)
    port = probe.port
    probe.shutdown()  # nobody listens on this port now
    with UdpTransport("127.0.0.1", port) as board:
        for _ in range(5):
            assert board.send(b"\x01\0", timeout=0) == 2
            board.recv(timeout=0.01)
        assert board.refused >= 1
    with UdpTransport("127.0.0.1", 0, listen=True) as host:
        assert host.send(b"\x01\0", timeout=0) == 0  # no board heard yet: nowhere to send


def test_bad_addresses_and_options_say_what_to_write() -> None:
    assert parse_address("5005", "127.0.0.1") == ("127.0.0.1", 5005)
    assert parse_address("10.0.0.2:7", None) == ("10.0.0.2", 7)
    for text, default in (("5005", None), ("host:port", None), ("h:70000", None)):
        with pytest.raises(TransportError, match="HOST:PORT|port must"):
            parse_address(text, default)
    with pytest.raises(TransportError, match="bitrate"):
        UdpTransport("127.0.0.1", 9, bitrate=0)
    with UdpTransport("127.0.0.1", 0, listen=True) as a, pytest.raises(TransportError,
                                                                        match="bind"):
        UdpTransport("127.0.0.1", a.port, listen=True)


def test_a_starved_receive_buffer_is_reported(caplog) -> None:
    """A receiver asks the kernel for its socket buffer and says when it got less (asked vs
    granted, and the setting to raise); one that got what it asked says nothing."""
    import logging
    from pathlib import Path

    from skinhil.transports import UdpTransport

    rmem_max = int(Path("/proc/sys/net/core/rmem_max").read_text())
    with caplog.at_level(logging.WARNING):
        starved = UdpTransport("127.0.0.1", 0, listen=True, rcvbuf_bytes=4 * rmem_max)
    try:
        assert starved.rcvbuf_asked == 4 * rmem_max
        assert 0 < starved.rcvbuf_granted < starved.rcvbuf_asked
        assert any("net.core.rmem_max" in r.getMessage() and str(starved.rcvbuf_granted)
                   in r.getMessage() for r in caplog.records)
    finally:
        starved.shutdown()
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        fine = UdpTransport("127.0.0.1", 0, listen=True, rcvbuf_bytes=65536)
    try:
        assert fine.rcvbuf_granted >= 65536 and not caplog.records
    finally:
        fine.shutdown()
