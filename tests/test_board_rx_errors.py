"""Every refused host command shows in the board's next STATUS (``rx_errors``, SPEC.md §3.3):
a NACKed command (an SNR out of range among them), a command whose CRC fails, a command
repeating the host's previous sequence number (dropped unanswered) and the host's own SYNC and
EVENTS packets, over a real pty."""

from __future__ import annotations

import os
import threading

import numpy as np
from harness.peers import PtyPeer

import protocols
from firmware_sim.board import Board, BoardConfig
from protocols.events import make_events
from skinhil.transports import SerialTransport


def _status_after_query(peer: PtyPeer) -> protocols.Status:
    """Send QUERY_STATUS; return the STATUS that follows its ACK."""
    token = peer.command(protocols.CommandCode.QUERY_STATUS)

    def answered(p: PtyPeer) -> bool:
        recs = p.records
        acks = [i for i, r in enumerate(recs) if isinstance(r, protocols.Ack)
                and r.token == token]
        return bool(acks) and any(isinstance(r, protocols.Status) for r in recs[acks[0]:])

    assert peer.wait_for(answered, 30), f"no answer to QUERY_STATUS {token}"
    recs = peer.records
    i = next(i for i, r in enumerate(recs) if isinstance(r, protocols.Ack) and r.token == token)
    return next(r for r in recs[i:] if isinstance(r, protocols.Status))


def test_refused_commands_show_in_the_next_status(pty_pair) -> None:
    peer = PtyPeer(pty_pair.master)
    board = Board(BoardConfig(seed=3, rest_s=0.05),
                  lambda: SerialTransport(pty_pair.path, baud=115200))
    stop = threading.Event()
    runner = threading.Thread(target=board.run, args=(30.0, stop), daemon=True)
    runner.start()
    try:
        base = _status_after_query(peer).rx_errors
        assert base == 0
        # a NACK: an unknown stimulus
        token = peer.command(protocols.CommandCode.SET_STIMULUS, 9999)
        assert _status_after_query(peer).rx_errors == base + 1
        assert any(isinstance(r, protocols.Ack) and r.token == token and not r.ok
                   for r in peer.records)
        # a bad CRC: one byte of a command packet changed (never to the delimiter)
        packet = bytearray(peer.encoder.command(protocols.Command(
            peer.next_token(), protocols.CommandCode.PING, 0)))
        packet[4] = packet[4] ^ 0x10 or 0x01
        os.write(pty_pair.master, bytes(packet))
        assert _status_after_query(peer).rx_errors == base + 2
        # a repeated host sequence number: the second copy is dropped, unanswered
        ping = peer.next_token()
        packet = bytearray(peer.encoder.command(protocols.Command(
            ping, protocols.CommandCode.PING, 0)))
        os.write(pty_pair.master, bytes(packet) * 2)
        assert _status_after_query(peer).rx_errors == base + 3
        assert sum(isinstance(r, protocols.Ack) and r.token == ping for r in peer.records) == 1
        # a host's own stream (a SYNC and an EVENTS packet) is no command: refused, counted
        ev = make_events(np.array([0, 100]), np.array([1, 2]))
        os.write(pty_pair.master, protocols.SerialEncoder().events(ev, 1_000))
        assert _status_after_query(peer).rx_errors == base + 5
        # an SNR out of its range is NACKed BAD_ARGUMENT
        token = peer.command(protocols.CommandCode.SET_SNR, -1000.0)
        assert _status_after_query(peer).rx_errors == base + 6
        assert any(isinstance(r, protocols.Ack) and r.token == token
                   and r.reason == protocols.NackReason.BAD_ARGUMENT for r in peer.records)
    finally:
        stop.set()
        runner.join(timeout=30)
        peer.close()
