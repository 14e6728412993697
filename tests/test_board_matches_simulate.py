"""The board streams what ``skinhil simulate`` computes offline: with the default mechanics
and readout (auto: geometric at 6x6, length readout), the same schedule, seed and noise give
the same spikes, event for event, over UDP as in the .npz file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from harness.peers import UdpPeer
from harness.serve import RUN_DIR, ServeProcess, serve_env

import protocols

SCHEDULE = """
[[event]]
start_s = 0.05
stimulus = "0deg_0.5N"

[[event]]
start_s = 0.45
stimulus = "120deg_0.3N"
"""
COMMON = ("--seed", "5", "--snr-db", "10", "--duration", "0.8")


def test_board_streams_the_same_spikes_as_simulate(tmp_path: Path) -> None:
    schedule = tmp_path / "two.toml"
    schedule.write_text(SCHEDULE, encoding="utf-8")
    out = tmp_path / "run.npz"
    offline = subprocess.run(
        [sys.executable, "-m", "skinhil", "simulate", "--schedule", str(schedule), *COMMON,
         "--out", str(out), "--no-progress"], cwd=RUN_DIR, env=serve_env(), text=True,
        capture_output=True, timeout=300)
    assert offline.returncode == 0, offline.stderr
    with np.load(out, allow_pickle=False) as run:
        expected = run["events"]
        meta = json.loads(str(run["meta"]))
    assert meta["mechanics"] == "geometric" and meta["readout"] == "length"

    peer = UdpPeer(versions=(3,))
    serve = ServeProcess("--udp", f"127.0.0.1:{peer.port}", "--schedule", str(schedule),
                         *COMMON, "--json")
    try:
        assert serve.wait(120) == 0, serve.stderr
        assert peer.wait_for(lambda p: p.decoder.counters.frames_ok > 0, 5)
        final = serve.summary()
        assert peer.wait_for(lambda p: len(p.events) >= final["sent"], 5)
    finally:
        serve.kill()
        peer.close()
    got = peer.events
    assert final["dropped"] == 0 and len(peer.of(protocols.Marker)) == 4
    assert len(expected) > 100  # both presses make the sensors fire
    np.testing.assert_array_equal(got["t"], expected["t"])
    np.testing.assert_array_equal(got["addr"], expected["addr"])
