"""``skinhil serve --udp`` on loopback (127.0.0.1): whole packets in every datagram, every
event and marker arrives, commands are answered, and the loss accounting is exact."""

from __future__ import annotations

import numpy as np
from harness.peers import UdpPeer
from harness.serve import ServeProcess

import protocols


def test_serve_udp_stream_is_complete_and_exact() -> None:
    peer = UdpPeer()
    serve = ServeProcess("--udp", f"127.0.0.1:{peer.port}", "--duration", "2.5", "--seed",
                         "4", "--json")
    try:
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 30)
        assert not serve.exited, serve.stderr
        token = peer.command(protocols.CommandCode.PING)
        assert serve.wait(40) == 0, serve.stderr
        assert peer.wait_for(lambda p: p.decoder.counters.frames_ok > 0, 1)
    finally:
        serve.kill()
        peer.close()
    assert set(peer.datagram_ends) == {0}  # every datagram ends a packet
    ev = peer.events
    summary = serve.summary()
    final = peer.of(protocols.Status)[-1]
    c = peer.decoder.counters
    assert len(ev) > 0 and np.all(np.diff(ev["t"]) >= 0)
    assert summary["generated"] == final.events_generated == final.events_sent == len(ev)
    assert c.frames_lost == 0 and c.events_lost == 0 and c.crc_errors == 0
    assert len(peer.of(protocols.Marker)) == summary["markers_sent"] > 0
    assert [a.ok for a in peer.of(protocols.Ack) if a.token == token] == [True]
