"""The link goes away mid-run (pty closed) and, with ``--reconnect``, comes back."""

from __future__ import annotations

import os
import time

from conftest import PtyPair
from harness.peers import PtyPeer
from harness.serve import ServeProcess

import protocols


def _wait(pred, timeout_s: float) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.02)
    return pred()


def _link_messages(serve: ServeProcess) -> list[str]:
    return [x["message"] for x in serve.lines if x.get("type") == "link"]


def test_serve_reconnects_when_the_port_returns(tmp_path) -> None:
    link = tmp_path / "ttyBOARD"
    first = PtyPair()
    os.symlink(first.path, link)
    serve = ServeProcess("--port", str(link), "--reconnect", "--json", "--snr-db", "30")
    peer1 = PtyPeer(first.master)
    second = None
    try:
        assert peer1.wait_for(lambda p: len(p.of(protocols.Status)) >= 2 or serve.exited, 30)
        assert not serve.exited, serve.stderr
        peer1.close()
        first.close()  # the device goes away
        assert _wait(lambda: any("lost" in m for m in _link_messages(serve)), 10), serve.lines
        time.sleep(0.3)
        second = PtyPair()  # ... and comes back under the same name
        tmp = tmp_path / "ttyBOARD.new"
        os.symlink(second.path, tmp)
        os.replace(tmp, link)
        peer2 = PtyPeer(second.master)
        assert peer2.wait_for(lambda p: len(p.of(protocols.Status)) >= 2, 10), serve.stderr
        assert any("back" in m for m in _link_messages(serve))
        serve.interrupt()
        assert serve.wait(20) == 130, serve.stderr  # stopped cleanly by Ctrl-C
        peer2.wait_for(lambda p: p.of(protocols.RunEnd), 2)
        peer2.close()
    finally:
        serve.kill()
        if second is not None:
            second.close()
    s = serve.summary()
    assert s["link_losses"] == 1
    assert s["generated"] == s["sent"] + s["dropped"] + s["queued"]
    last = peer2.of(protocols.Status)[-1]
    assert last.events_queued == 0
    assert last.events_generated == s["generated"]
    # each link opens with the session: at the start, then after the reconnection; the run's
    # end is on the wire with its reason (SIGINT)
    first_session, session = peer1.records[0], peer2.records[0]
    assert isinstance(first_session, protocols.Session) and isinstance(session, protocols.Session)
    assert first_session.reason == protocols.SessionReason.START
    assert session.reason == protocols.SessionReason.RECONNECT
    assert (session.snr_db, session.n_channels, session.step_us, session.n_stimuli) == (
        30.0, 338, 100, 14)
    table = peer2.records[1:1 + session.n_stimuli]
    assert protocols.table_digest(table) == session.table_digest
    assert peer2.records[-1] == protocols.RunEnd(last.t_us, protocols.RunEndReason.SIGNAL)
    assert last.dropped_link_down == s["dropped_by"]["link_down"]


def test_serve_without_reconnect_says_the_link_went_away(pty_pair) -> None:
    serve = ServeProcess("--port", pty_pair.path, "--json")
    peer = PtyPeer(pty_pair.master)
    try:
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 30)
        peer.close()
        pty_pair.close()
        rc = serve.wait(10)
    finally:
        serve.kill()
    lines = [ln for ln in serve.stderr.splitlines() if ln.strip()]
    assert rc != 0 and "Traceback" not in serve.stderr
    assert len(lines) == 1 and lines[0].startswith("skinhil: error: ")
    assert "went away" in lines[0] and "--reconnect" in lines[0]
