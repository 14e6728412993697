"""A board whose skin has more than 338 channels streams the wide format (version 4) on CAN:
an 8x8 skin (706 channels) on a python-can virtual bus, classic and FD, decoded by a
decoder that reads only version 4; every event arrives, with addresses above 337."""

from __future__ import annotations

import random
import threading

import pytest

import protocols
from firmware_sim.board import Board, BoardConfig
from skinhil.transports import CanTransport


@pytest.mark.parametrize("fd", [False, True])
def test_wide_board_on_can(fd: bool) -> None:
    chan = f"wide-{random.getrandbits(32)}"
    host = CanTransport(chan, "virtual", fd=fd)
    board = Board(BoardConfig(size=(8, 8), seed=2, rest_s=0.05),
                  lambda: CanTransport(chan, "virtual", fd=fd))
    assert board.link is not None and board.link.encoder.version == 4
    done: list = []
    t = threading.Thread(target=lambda: done.append(board.run(1.0)))
    t.start()
    dec = protocols.CanDecoder(board_id=0, fd=fd, versions=(4,))
    events, classes = [], set()
    while True:
        alive = t.is_alive()
        frames = host.recv(0.05 if alive else 0.3)
        if not alive and not frames:
            break
        classes |= {f.arbitration_id >> 4 for f in frames}
        events.append(dec.feed(frames).events)
    host.shutdown()
    s = done[0]
    got = sum(len(e) for e in events)
    assert got == s.sent == s.generated > 0
    assert max(int(e["addr"].max()) for e in events if len(e)) >= protocols.N_CHANNELS
    assert 7 in classes and 6 not in classes  # WIDE_EVENTS frames only
    assert dec.counters.frames_lost == dec.counters.events_lost == 0
