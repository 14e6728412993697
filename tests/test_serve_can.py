"""``skinhil serve --can vcan0``: the board on a real CAN bus, decoded with protocols.

Needs a real vcan0: runs directly where the host has one, else inside user-mode Linux
(tests/test_transport_vcan_uml.py), where system calls are slow: rates here are moderate.
"""

from __future__ import annotations

import numpy as np
import pytest
from harness.peers import CanPeer
from harness.serve import ServeProcess

import protocols


@pytest.mark.vcan
@pytest.mark.parametrize("fd", [False, True], ids=["classic", "fd"])
def test_serve_on_vcan(fd: bool) -> None:
    # no --duration: inside UML a 2 s run can end before the slower peer has decoded its
    # first status, so the commands go out while it runs and Ctrl-C (SIGINT) ends it
    min_board_s = 2.0
    peer = CanPeer("vcan0", fd=fd, board_id=3)
    extra = ["--fd"] if fd else []
    serve = ServeProcess("--can", "vcan0", "--board-id", "3", "--seed", "1", "--json", *extra)
    try:
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 120)
        assert not serve.exited, serve.stderr
        codes = protocols.CommandCode
        t_ok = peer.command(codes.QUERY_STATUS)
        t_bad = peer.command(codes.SET_SCHEDULE, 77)
        assert peer.wait_for(lambda p: {a.token for a in p.of(protocols.Ack)} >= {t_ok, t_bad}
                             and p.of(protocols.Status)[-1].t_us >= min_board_s * 1e6, 60)
        serve.interrupt()
        assert serve.wait(60) == 130, serve.stderr  # stopped cleanly by Ctrl-C
        end_us = round(serve.summary()["board_time_s"] * 1e6)
        peer.wait_for(lambda p: p.of(protocols.Status)[-1].t_us >= end_us, 5)
    finally:
        serve.kill()
        peer.close()
    ev = peer.events
    assert len(ev) > 0 and np.all(ev["t"] % 100 == 0) and np.all(np.diff(ev["t"]) >= 0)
    s = serve.summary()
    final = peer.of(protocols.Status)[-1]
    assert final.events_generated == final.events_sent + final.events_dropped \
        + final.events_queued
    assert final.events_sent == len(ev) == s["sent"]
    assert peer.bus.rx_overflows == 0 and peer.decoder.counters.frames_lost == 0
    markers = peer.of(protocols.Marker)
    assert markers and markers[0].t_us == 100_000 and markers[0].phase == \
        protocols.MarkerPhase.ONSET
    acks = {a.token: a for a in peer.of(protocols.Ack)}
    assert acks[t_ok].ok
    assert not acks[t_bad].ok and acks[t_bad].reason == protocols.NackReason.UNKNOWN_SCHEDULE
