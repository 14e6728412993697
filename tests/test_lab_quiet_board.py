"""A quiet board (STATUS records, no spike) still moves the live view's clock and PSP traces
and the LSL PSP stream: their time follows the board's STATUS, not only its spikes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from harness.lab import chance_model

import protocols
from skinhil.events import EVENT_DTYPE
from skinhil.model.geometry import build_mesh
from skinhil.model.skin import SkinParams
from skinhil.receiver import Receiver
from skinhil.receiver.model_file import load_window_decoder
from skinhil.transports import UdpTransport
from skinhil.view import ViewFeed


def _status(t_us: int, queued: int = 0) -> protocols.Status:
    return protocols.Status(t_us=t_us, events_generated=1 + queued, events_sent=1,
                            events_dropped=0, events_queued=queued, late_ticks=0,
                            rx_errors=0, running=True)


@pytest.fixture
def receiver(tmp_path: Path) -> Receiver:
    decoder = load_window_decoder(chance_model(tmp_path, (6, 6)), n_channels=338)
    with UdpTransport("127.0.0.1", 0, listen=True) as link:
        yield Receiver(link, decoder)


def test_status_moves_the_view_clock_and_traces_of_a_quiet_board(receiver: Receiver) -> None:
    p = SkinParams()
    feed = ViewFeed(receiver, build_mesh(p.spacing_m, p.layer_gap_m), {}, [0, 5])
    receiver.add_listener(feed)
    enc = protocols.SerialEncoder()
    one = np.zeros(1, dtype=EVENT_DTYPE)
    one["t"], one["addr"], one["p"] = 100_000, 5, 1
    receiver.feed(enc.events(one, 100_100) + enc.status(_status(200_000)))
    first = feed.update()
    assert first["t_board_us"] == 200_000 and first["run"]["state"] == "live"
    # 4.5 s of board time with nothing but STATUS: the clock and the traces go on
    for t in range(1_000_000, 5_000_001, 500_000):
        receiver.feed(enc.status(_status(t)))
    later = feed.update()
    assert later["t_board_us"] == 5_000_000
    assert later["psp"]["first"] + later["psp"]["n"] == 5_000  # 1 kHz samples up to 5 s
    # a STATUS stamped ahead of events still queued on the board moves the clock but not
    # the traces (those events' PSP is still to come)
    receiver.feed(enc.status(_status(6_000_000, queued=3)))
    ahead = feed.update()
    assert ahead["t_board_us"] == 6_000_000 and ahead["psp"]["n"] == 0
    # the receiver stopping ends the run on the page
    feed.end_run("the receiver stopped")
    assert feed.update()["run"] == {"state": "ended", "reason": "the receiver stopped"}
