"""`listen --lsl`: every LSL outlet read back by a pylsl inlet on this machine (loopback only,
through an lsl_api.cfg), against the session the same receiver recorded."""

from __future__ import annotations

import os
import re
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from harness.lab import LOOPBACK_LSL_CFG, listening, stop
from harness.serve import ServeProcess

pylsl = pytest.importorskip("pylsl")

from skinhil.lsl.outlets import LINK_CHANNELS  # noqa: E402

STREAMS = ("spikes", "psp", "markers", "decisions", "link")


@pytest.fixture
def loopback_lsl(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    cfg = tmp_path / "lsl_api.cfg"
    cfg.write_text(LOOPBACK_LSL_CFG)
    monkeypatch.setenv("LSLAPICFG", str(cfg))


class Reader:
    """Pulls one stream on a thread: samples, their LSL stamps and local arrival times."""

    def __init__(self, info: Any) -> None:
        self.inlet = pylsl.StreamInlet(info, max_buflen=60)
        self.inlet.open_stream(10)
        self.info = self.inlet.info(10)
        self.samples: list[Any] = []
        self.stamps: list[float] = []
        self.arrived: list[float] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop.is_set():
            chunk, stamps = self.inlet.pull_chunk(timeout=0.05, max_samples=100_000)
            if stamps:
                now = pylsl.local_clock()
                self.samples += chunk
                self.stamps += stamps
                self.arrived += [now] * len(stamps)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)


def _channels(info: Any) -> list[dict[str, str]]:
    out, ch = [], info.desc().child("channels").child("channel")
    while not ch.empty():
        out.append({k: ch.child_value(k) for k in ("label", "unit", "type")})
        ch = ch.next_sibling()
    return out


def test_every_lsl_outlet_reads_back_as_the_receiver_decoded(
        tmp_path: Path, loopback_lsl: None) -> None:
    session = tmp_path / "session.npz"
    with listening(tmp_path, "--lsl", "skinhil-test", "--record", str(session),
                   ready="LSL outlets") as (listen, board_end):
        readers = {}
        for kind in STREAMS:
            found = pylsl.resolve_byprop("name", f"skinhil-test-{kind}", timeout=10)
            assert len(found) == 1, kind
            readers[kind] = Reader(found[0])
        board = ServeProcess("--port", str(board_end), "--duration", "4", "--seed", "1",
                             "--snr-db", "10", "--rest", "0.3", "--json")
        try:
            assert board.wait(120) == 0, board.stderr
        finally:
            board.kill()
        time.sleep(1.0)
        stop(listen)  # the outlets push what they kept, then close
        time.sleep(1.5)
        for r in readers.values():
            r.close()
    summary = [x for x in listen.lines if x.get("type") == "summary"][-1]
    rec = np.load(session)
    events, markers, decisions = rec["events"], rec["markers"], rec["decisions"]
    assert summary["link"]["events_decoded"] == len(events) > 1000

    # spikes: one sample per event, value = address, in the receiver's order
    spikes = readers["spikes"]
    assert spikes.info.type() == "Spikes" and spikes.info.nominal_srate() == 0
    assert spikes.info.channel_format() == pylsl.cf_int32
    assert _channels(spikes.info) == [{"label": "sensor", "unit": "address",
                                       "type": "SpikeAddress"}]
    first = spikes.info.desc().child("sensors").child("sensor")
    assert (first.child_value("address"), first.child_value("mass_i"),
            first.child_value("mass_j")) == ("0", "M1", "M2")
    addr = np.array([s[0] for s in spikes.samples])
    assert len(addr) == len(events)
    np.testing.assert_array_equal(addr, events["addr"])
    # stamps: board time mapped to the LSL clock by the receiver's clock model; never
    # later than the sample arrived
    offset = np.array(spikes.stamps) - events["t"] * 1e-6
    assert (np.array(spikes.arrived) >= np.array(spikes.stamps)).all()

    def mapped(board_us: np.ndarray) -> np.ndarray:
        """Board time (µs) on the LSL clock as the spike stream maps it (the offset of the
        latest spike at or before each time)."""
        i = np.searchsorted(events["t"], board_us, side="right") - 1
        return board_us * 1e-6 + offset[np.clip(i, 0, None)]

    # markers: the receiver's markers, in order, stamped at board time on the same mapping
    texts = [s[0] for s in readers["markers"].samples]
    assert readers["markers"].info.type() == "Markers"
    assert len(texts) == len(markers) >= 6
    got = [(m.group(1), int(m.group(2)), float(m.group(3))) for m in
           (re.match(r"(\w+) (\d+) \S+ t_board_s=([\d.]+)", t) for t in texts) if m]
    assert [(p, s) for p, s, _ in got] == [(str(m["phase"]), int(m["stimulus_id"]))
                                           for m in markers]
    np.testing.assert_allclose([t for _, _, t in got], markers["t_us"] * 1e-6, atol=1e-4)
    stamps = np.array(readers["markers"].stamps)
    board_s = markers["t_us"] * 1e-6
    assert (np.diff(stamps) > 0).all()
    assert np.abs(stamps - mapped(markers["t_us"])).max() < 2e-3, stamps - board_s

    # decisions: each decision, with its ground truth, at its board time
    dec = [s[0] for s in readers["decisions"].samples]
    assert len(dec) == len(decisions) >= 3
    for text, d in zip(dec, decisions, strict=True):
        assert text.startswith(f"decision {int(d['label'])} ")
        truth = "-" if d["true_label"] < 0 else str(int(d["true_label"]))
        assert f" true={truth} " in text
    decided = np.array(readers["decisions"].stamps)
    assert np.abs(decided - mapped(decisions["decided_t_us"])).max() < 2e-3

    # PSP: 1 kHz, one channel per sensor with its spring's masses, unit and place (XDF:
    # location X/Y/Z in mm; sensor 0 joins M1-M2 at the top layer's top-left edge)
    psp = readers["psp"]
    assert psp.info.nominal_srate() == 1000 and psp.info.channel_count() == 338
    labels = _channels(psp.info)
    assert labels[0] == {"label": "S0 M1-M2", "unit": "a.u.", "type": "PSP"}
    loc = psp.info.desc().child("channels").child("channel").child("location")
    x, y, z = (float(loc.child_value(a)) for a in "XYZ")
    assert x < 0 < y and z == 0.0
    # provenance in every stream's desc
    for r in readers.values():
        prov = r.info.desc().child("provenance")
        assert prov.child_value("size") == "6x6" and prov.child_value("sensors") == "338"
        assert len(prov.child_value("decoder_sha256")) == 64
        assert prov.child_value("skinhil_version")
        assert r.info.desc().child("acquisition").child_value("manufacturer") == "skinhil"
    # the PSP stream covers the whole session: from its first item to the board's last
    # STATUS, not only up to the last spike
    values = np.array(psp.samples)
    board_end_s = board.summary()["board_time_s"]
    assert values.shape[0] >= (events["t"][-1] - events["t"][0]) * 1e-3
    assert abs(psp.stamps[-1] - mapped(np.array([int(board_end_s * 1e6)]))[0]) < 0.05
    # link health: one sample per STATUS, the receiver's counters; the last one whole
    link = readers["link"]
    assert link.info.type() == "LinkHealth"
    names = [c["label"] for c in _channels(link.info)]
    assert tuple(names) == LINK_CHANNELS and link.info.channel_count() == len(LINK_CHANNELS)
    last = dict(zip(names, link.samples[-1], strict=True))
    assert last["events_decoded"] == len(events) and last["board_generated"] == len(events)
    assert len(link.samples) >= 3 and (np.diff(link.stamps) >= 0).all()
    assert np.median(np.diff(psp.stamps)) == pytest.approx(1e-3, abs=1e-6)
    # each sensor's PSP integrates to tau_m (21.3 ms) per spike: total ≈ spikes × tau_m
    counts = np.bincount(events["addr"], minlength=338)
    busy = counts > 50
    area = values.sum(axis=0) * 1e-3
    np.testing.assert_allclose(area[busy], counts[busy] * 21.3e-3, rtol=0.05)
    assert os.environ["LSLAPICFG"].endswith("lsl_api.cfg")
