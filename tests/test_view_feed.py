"""The live view's feed and server without a browser: a quiet board (STATUS records, no
spike) still moves the clock and the PSP traces; the run's end state; a page's PSP pick; one
server showing several boards, each page the one it asks for, and the ``end`` event."""

from __future__ import annotations

import json
import threading
import time
import urllib.request
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
from skinhil.view import ViewFeed, ViewServer


def _status(t_us: int, queued: int = 0) -> protocols.Status:
    return protocols.Status(t_us=t_us, events_generated=1 + queued, events_sent=1,
                            events_dropped=0, events_queued=queued, late_ticks=0,
                            rx_errors=0, running=True)


@pytest.fixture
def receiver(tmp_path: Path) -> Receiver:
    decoder = load_window_decoder(chance_model(tmp_path, (6, 6)), n_channels=338)
    with UdpTransport("127.0.0.1", 0, listen=True) as link:
        yield Receiver(link, decoder)


def _feed(receiver: Receiver, sensors: list[int] | None = None) -> ViewFeed:
    p = SkinParams()
    return ViewFeed(receiver, build_mesh(p.spacing_m, p.layer_gap_m), {}, sensors)


def test_status_moves_the_view_clock_and_traces_of_a_quiet_board(receiver: Receiver) -> None:
    feed = _feed(receiver, [0, 5])
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


def _events(url: str, count: int = 0) -> list[tuple[str, dict]]:
    """The server-sent events of ``url`` as (event, data): the first ``count``, or (0)
    until the ``end`` event."""
    out: list[tuple[str, dict]] = []
    event = None
    with urllib.request.urlopen(url, timeout=10) as resp:
        for raw in resp:
            line = raw.decode().rstrip("\n")
            if line.startswith("event: "):
                event = line[7:]
            elif line.startswith("data: "):
                out.append((str(event), json.loads(line[6:])))
                if len(out) == count or event == "end":
                    break
    return out


def test_one_server_shows_several_boards_takes_picks_and_ends_the_run(
        receiver: Receiver) -> None:
    first, second = _feed(receiver), _feed(receiver)
    server = ViewServer(first, period_s=0.05).start()
    try:
        server.add_feed("127.0.0.1:5001", second)
        (kind, hello), = _events(server.url + "events?board=127.0.0.1:5001", 1)
        assert kind == "config" and hello["board"] == "127.0.0.1:5001"
        assert hello["boards"] == ["0", "127.0.0.1:5001"]
        assert hello["grid"] == [6, 6] and len(hello["sensor_xy"]) > 0
        (_, default), (kind, update) = _events(server.url + "events", 2)
        assert default["board"] == "0"
        assert kind == "update" and update["boards"] == ["0", "127.0.0.1:5001"]
        # a page picks PSP sensors: that board's next update and config say so
        req = urllib.request.Request(server.url + "psp", method="POST", data=json.dumps(
            {"board": "127.0.0.1:5001", "sensors": [7, 7, 400, 3]}).encode())
        urllib.request.urlopen(req, timeout=10).close()
        assert second.hello()["psp_sensors"] == [7, 3]  # repeats and non-sensors left out
        labels = second.update()["psp_labels"]
        assert [a.split()[0] for a in labels] == ["S7", "S3"], labels
        assert first.hello()["psp_sensors"] != [7, 3]
        # a page connected when the server closes gets a last update and the end event
        seen: list[tuple[str, dict]] = []
        reader = threading.Thread(target=lambda: seen.extend(_events(server.url + "events")))
        reader.start()
        time.sleep(0.5)
    finally:
        server.close("the receiver stopped")
    reader.join(10)
    assert seen[-1] == ("end", {"state": "ended", "reason": "the receiver stopped"}), seen[-3:]
    assert seen[-2][0] == "update" and seen[-2][1]["run"]["state"] == "ended"


def test_the_grasp_key_carries_the_boards_held_object_truth(receiver: Receiver,
                                                             tmp_path: Path) -> None:
    """The held object's truth, through the file the board appends it to and the feed: each
    10 ms point is its bin's last tick (grip while held, else none; normal force, load, slip
    distance) with the bin's highest slip state; lift 1 is marked held at its last tick,
    lift 2 dropped at the tick it dropped; a page that connects later gets the points in its
    config."""
    from skinhil.plant import HELD_DTYPE
    from skinhil.plant.truth_file import HeldTruthReader, HeldTruthWriter
    from skinhil.view.grasp_trace import BIN_US, GraspTrace

    rng = np.random.default_rng(3)
    n = 200  # 1 ms ticks: lift 1 for 0-79 ms, none 80-99 ms, lift 2 from 100 ms, drops at 150
    truth = np.zeros(n, dtype=HELD_DTYPE)
    truth["t_us"] = np.arange(n) * 1000
    truth["lift"] = np.where(truth["t_us"] < 80_000, 1, np.where(truth["t_us"] < 100_000, 0, 2))
    truth["dropped"] = truth["t_us"] >= 150_000
    truth["held"] = (truth["lift"] > 0) & ~truth["dropped"]
    for field in ("grip_n", "normal_n", "load_n", "slip_distance_mm"):
        truth[field] = rng.uniform(0, 1, n)
    truth["slip"] = rng.integers(0, 4, n)
    writer = HeldTruthWriter(tmp_path / "truth.bin")
    reader = HeldTruthReader(tmp_path / "truth.bin")
    trace = GraspTrace()
    feed = ViewFeed(receiver, build_mesh(SkinParams().spacing_m, SkinParams().layer_gap_m), {},
                    grasp=trace)
    assert "grasp" not in _feed(receiver).update()  # no held object: no panel
    for row in truth[:123]:
        writer.add(row[None])
    writer.flush()
    trace.add(reader.read())  # mid-bin: the open bin waits
    first = feed.update()["grasp"]
    for row in truth[123:]:
        writer.add(row[None])
    writer.close()
    trace.add(reader.read())
    trace.finish()
    rest = feed.update()["grasp"]
    got = {k: first[k] + rest[k] for k in first if k != "outcomes"}
    assert reader.read().shape == (0,)
    assert len(first["t_us"]) == 12 and len(got["t_us"]) == n * 1000 // BIN_US
    last = np.arange(9, n, 10)  # each bin's last tick
    assert got["t_us"] == truth["t_us"][last].tolist()
    for key, field in (("normal_n", "normal_n"), ("load_n", "load_n"),
                       ("slip_mm", "slip_distance_mm")):
        assert np.allclose(got[key], truth[field][last], atol=5e-5), key
    held = truth["held"][last]  # the grip on the object: none between lifts and once dropped
    assert [g is None for g in got["grip_n"]] == (~held).tolist()
    assert np.allclose([g for g in got["grip_n"] if g is not None], truth["grip_n"][last][held],
                       atol=5e-5)
    assert got["slip"] == truth["slip"].reshape(-1, 10).max(axis=1).tolist()
    assert got["lift"] == truth["lift"][last].tolist()
    assert first["outcomes"] == [{"lift": 1, "t_us": 79_000, "held": True}]
    assert rest["outcomes"] == [{"lift": 2, "t_us": 150_000, "held": False}]
    hello = feed.hello()["grasp"]
    assert hello["t_us"] == got["t_us"] and len(hello["outcomes"]) == 2


def test_a_late_page_gets_the_last_seconds_of_the_stream(receiver: Receiver) -> None:
    """The ``config`` of a page that connects 15 s into a run holds the updates of the last
    10 s of board time that brought spikes or markers, in order, ending with the newest;
    a PSP pick leaves the samples of the sensors shown before out of them."""
    from skinhil.view.feed import HISTORY_S

    feed = _feed(receiver, [0, 5])
    receiver.add_listener(feed)
    enc = protocols.SerialEncoder()
    assert feed.hello()["history"] == []
    feed.update()  # nothing received yet: nothing kept
    for k in range(1, 151):  # 15 s, one spike each 0.1 s
        one = np.zeros(1, dtype=EVENT_DTYPE)
        one["t"], one["addr"], one["p"] = k * 100_000, k % 338, 1
        receiver.feed(enc.events(one, k * 100_000 + 100))
        last = feed.update()
    history = feed.hello()["history"]
    times = [h["t_board_us"] for h in history]
    assert times == sorted(times) and times[-1] == last["t_board_us"] == 15_000_000
    assert times[0] >= 15_000_000 - HISTORY_S * 1e6 and len(history) >= 99, times[:3]
    assert [h["seq"] for h in history] == list(range(history[0]["seq"], last["seq"] + 1))
    assert sum(h["spikes"]["n"] for h in history) == len(history)
    assert any(h["psp"]["n"] for h in history)
    feed.pick_psp_sensors([7])
    assert not any(h["psp"]["n"] for h in feed.hello()["history"])
    assert feed.hello()["map_shape"] == [10, 10] and feed.hello()["map"]["z"]
