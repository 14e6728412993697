"""At the end of a saturated run the board drops what its FIFO still holds (counted as
``shutdown``) but still sends every ground-truth marker that fell due."""

from __future__ import annotations

import numpy as np
from harness.peers import PtyPeer

import protocols
from firmware_sim.board import Board, BoardConfig
from skinhil.model.timeline import Timeline
from skinhil.transports import SerialTransport


def test_markers_survive_a_shutdown_that_drops_queued_events(pty_pair) -> None:
    duration_s = 1.0
    config = BoardConfig(snr_db=-10.0, seed=3, rest_s=0.05, drain_timeout_s=0.2)
    peer = PtyPeer(pty_pair.master)
    try:
        board = Board(config, lambda: SerialTransport(pty_pair.path, baud=9600))
        summary = board.run(duration_s)
        assert peer.wait_for(lambda p: any(
            s.t_us >= duration_s * 1e6 for s in p.of(protocols.Status)), 5)
    finally:
        peer.close()
    timeline = Timeline(config.dt_s, None, config.seed, config.rest_s)
    timeline.forces(np.array([0.0, duration_s]))
    due = [(m.t_us, m.stimulus_id) for m in timeline.markers_before(int(duration_s * 1e6))]
    got = [(m.t_us, m.stimulus_id) for m in peer.of(protocols.Marker)]
    assert summary.dropped_by["shutdown"] > 0  # the run did end with events queued
    assert len(due) >= 4 and got == due
    assert summary.markers_sent == len(due) and summary.markers_dropped == 0
    final = peer.of(protocols.Status)[-1]
    assert final.events_generated == final.events_sent + final.events_dropped
    assert final.events_dropped == summary.dropped
