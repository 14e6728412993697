"""Loss accounting without holes: every status on the wire, the last one included, closes
the account of events and ground-truth markers, through a STOP, an overloaded link and a
shutdown that drops what is still queued; live status keeps flowing when every tick is late."""

from __future__ import annotations

import threading
import time

from harness.peers import PtyPeer

import protocols
from firmware_sim.board import Board, BoardConfig
from skinhil.model.timeline import Timeline
from skinhil.transports import SerialTransport


def _check_account(s: protocols.Status) -> None:
    assert s.events_generated == s.events_sent + s.events_dropped + s.events_queued, s
    assert s.events_dropped == (s.dropped_fifo_full + s.dropped_stopped
                                + s.dropped_link_down + s.dropped_shutdown), s


def test_every_status_closes_the_account_through_stop_overload_and_shutdown(pty_pair) -> None:
    duration_s = 1.5
    config = BoardConfig(snr_db=-10.0, seed=4, rest_s=0.05, fifo_events=400,
                         drain_timeout_s=0.0)  # what is queued at the end is dropped
    peer = PtyPeer(pty_pair.master)
    codes = protocols.CommandCode

    def host() -> None:  # STOP at 0.4 s of board time, START again at 0.8 s (its statuses)
        for opcode, at_s in ((codes.STOP, 0.4), (codes.START, 0.8)):
            peer.wait_for(lambda p, t=at_s * 1e6: any(
                s.t_us >= t for s in p.of(protocols.Status)), 60)
            peer.command(opcode)

    try:
        board = Board(config, lambda: SerialTransport(pty_pair.path, baud=115200))
        threading.Thread(target=host, daemon=True).start()
        summary = board.run(duration_s)
        assert peer.wait_for(lambda p: p.of(protocols.RunEnd), 10)
    finally:
        peer.close()
    statuses = peer.of(protocols.Status)
    assert len(statuses) >= 5
    for s in statuses:
        _check_account(s)
    final = statuses[-1]
    assert peer.records[-2] == final  # the account closes the stream, then the run ends
    assert peer.records[-1] == protocols.RunEnd(final.t_us, protocols.RunEndReason.DURATION)
    # the run went through each loss: an overloaded link, a STOP, a shutdown with a backlog
    assert final.dropped_fifo_full > 0 and final.dropped_stopped > 0
    assert final.dropped_shutdown > 0 and final.events_queued == 0
    assert any(not s.running for s in statuses) and final.running
    # the receiver got exactly what the board says it sent (a clean pty loses nothing)
    assert final.events_sent == len(peer.events) == summary.sent
    assert peer.decoder.counters.events_lost == 0
    # every marker that fell due is counted: sent (and received) or dropped while stopped
    due = Timeline(config.dt_s, seed=config.seed, rest_s=config.rest_s).markers_before(
        int(round(duration_s * 1e6)))
    markers = peer.of(protocols.Marker)
    assert final.markers_sent == len(markers) == summary.markers_sent
    assert final.markers_dropped == summary.markers_dropped > 0
    assert final.markers_sent + final.markers_dropped == len(due)
    got = {(m.t_us, m.stimulus_id) for m in markers}
    lost = [m for m in due if (m.t_us, m.stimulus_id) not in got]
    assert len(lost) == final.markers_dropped
    stopped = [s.t_us for s in statuses if not s.running]
    assert all(min(stopped) - 2e5 <= m.t_us <= max(stopped) + 2e5 for m in lost)


def test_live_status_flows_when_every_tick_is_late(pty_pair) -> None:
    """Ticks of 10 µs cannot be kept: every tick is late, yet the live status is reported
    at least every two report periods (rate-limited, never starved)."""
    config = BoardConfig(dt_s=1e-5, tick_s=1e-5, snr_db=20.0)
    peer = PtyPeer(pty_pair.master)
    board = Board(config, lambda: SerialTransport(pty_pair.path, baud=921600))
    calls: list[float] = []
    stop = threading.Event()
    period_s = 0.2

    def on_second(b: Board) -> None:
        calls.append(time.monotonic())
        if len(calls) == 1:
            threading.Timer(2.0, stop.set).start()

    try:
        board.run(None, stop, on_second, report_period_s=period_s)
    finally:
        peer.close()
    assert board.clock.deadline_misses >= 0.9 * board.clock.ticks
    assert len(calls) >= 5
    gaps = [b - a for a, b in zip(calls, calls[1:], strict=False)]
    assert min(gaps) >= period_s * 0.9 and max(gaps) <= 2 * period_s + 0.1
