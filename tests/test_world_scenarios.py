"""Every example scenario (examples/scenarios) plays through ``simulate`` and through
``serve`` on a real pty; the contacts' truth stays on the board; bad contact tables are
refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from harness.peers import PtyPeer

import protocols
from skinhil.cli import main
from skinhil.world import TRUTH_DTYPE
from skinhil.world.scenario_file import load_scenario

SCENARIOS = sorted((Path(__file__).resolve().parents[1] / "examples" / "scenarios").glob(
    "*.toml"))


def test_the_examples_hold_the_cases_the_docs_name() -> None:
    names = {p.stem for p in SCENARIOS}
    assert {"press", "slide", "vibrate_100hz", "vibrate_250hz", "tap", "slip"} <= names
    shapes = {c.indenter.shape for p in SCENARIOS
              for c in (load_scenario(p).scene or ()).contacts}  # type: ignore[union-attr]
    assert shapes == {"sphere", "flat", "edge", "pins"}


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_a_scenario_plays_through_simulate(path: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.npz"
    assert main(["simulate", "--schedule", str(path), "--out", str(out), "--no-progress"]) == 0
    said = capsys.readouterr().out
    strain = float(said.split("max strain ")[1].split(" %")[0])
    assert 0 < strain < 10  # within the bound: the default skin's touches stay near-linear
    data = np.load(out)
    truth, meta = data["truth"], json.loads(str(data["meta"]))
    scenario = load_scenario(path)
    n_contacts = len(scenario.scene.contacts)  # type: ignore[union-attr]
    assert truth.dtype == TRUTH_DTYPE and meta["max_strain"] == pytest.approx(strain / 100, 1e-2)
    assert len(truth) == n_contacts * round(meta["duration_s"] / 1e-3)
    assert np.all(np.diff(truth["t_us"].reshape(-1, n_contacts)[:, 0]) == 1000)
    touching = truth[truth["nodes"] > 0]
    assert len(touching) and np.all(touching["normal_n"] > 0)
    assert np.allclose(touching["area_mm2"], touching["nodes"] * 1.0)  # 1 mm² per mass
    if path.stem == "slip":  # stick, then gross slip (the ball touches two masses, which
        slip = touching["slip"]  # slip together on the default skin)
        assert slip[0] == 1 and 3 in slip
        assert np.all(slip[:np.flatnonzero(slip == 3)[0]] == 1)
    if path.stem.startswith("vibrate"):
        hz = float(path.stem.split("_")[1][:-2])
        depth = truth[truth["active"]]["indenter_depth_mm"]  # every tick of the press
        spectrum = np.abs(np.fft.rfft(depth - depth.mean()))
        assert np.fft.rfftfreq(len(depth), 1e-3)[np.argmax(spectrum)] == pytest.approx(hz, 0.05)
    assert len(data["events"]) > 0


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_a_scenario_plays_through_serve_on_a_pty(path: Path, pty_pair, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    common = ["--schedule", str(path), "--duration", "0.3", "--seed", "1", "--snr-db", "10"]
    peer = PtyPeer(pty_pair.master)
    try:
        code = main(["serve", "--port", pty_pair.path, *common, "--json"])
        assert code == 0
        assert peer.wait_for(lambda p: p.of(protocols.Status), 5)
    finally:
        peer.close()
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines() if x.startswith("{")]
    summary = next(x for x in lines if x["type"] == "summary")
    truth = next(x for x in lines if x["type"] == "truth")
    assert truth["ticks"] >= 250 and truth["peak_normal_n"] > 0  # kept by the board
    assert summary["sent"] == len(peer.events) > 0
    # the link carries events, status, the stimuli's markers and the session records (the
    # stimulus table, the run's end) only: no contact truth
    kinds = {type(r).__name__ for r in peer.records}
    assert kinds <= {"Sync", "Status", "Marker", "Ack", "Session", "StimulusEntry", "SuiteEntry",
                     "RunEnd"}
    markers = {m.stimulus_id for m in peer.of(protocols.Marker)}
    assert markers == ({10} if path.stem == "edge_and_pins" else set())
    # the board plays what simulate computes offline for the same seed, event for event
    out = tmp_path / "run.npz"
    assert main(["simulate", *common, "--out", str(out), "--no-progress"]) == 0
    expected = np.load(out)["events"]
    assert np.array_equal(peer.events["t"], expected["t"])
    assert np.array_equal(peer.events["addr"], expected["addr"])


BAD = {
    "unknown key": ('[[contact]]\nindenter = "p"\nmotion = "press"\ndepth_mm = 0.5\n'
                    'speed = 3\n', "unknown key(s) speed"),
    "too deep": ('[[contact]]\nindenter = "p"\nmotion = "press"\ndepth_mm = 9.0\n',
                 "depth_mm = 9.0"),
    "no indenter": ('[[contact]]\nindenter = "q"\nmotion = "press"\ndepth_mm = 0.5\n',
                    "indenter = 'q'"),
    "depth and load": ('[[contact]]\nindenter = "p"\nmotion = "press"\ndepth_mm = 0.5\n'
                       'load_n = 0.2\n', "one of them"),
    "bad shape": ('[[indenter]]\nname = "r"\nshape = "cube"\n', "shape = 'cube'"),
    "friction": ('[[contact]]\nindenter = "p"\nmotion = "press"\ndepth_mm = 0.5\n'
                 'mu_static = 0.2\nmu_kinetic = 0.5\n', "mu_kinetic <= mu_static"),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test_bad_contact_tables_are_refused_in_one_line(case: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    text, says = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text('[[indenter]]\nname = "p"\nshape = "sphere"\nradius_mm = 2.0\n\n' + text)
    assert main(["simulate", "--schedule", str(path), "--out", str(tmp_path / "x.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("skinhil: error:") and says in err[0], err


def test_simulate_writes_the_truth_to_nwb(tmp_path: Path) -> None:
    from pynwb import NWBHDF5IO, validate
    from test_nwb import inspector_findings

    path = next(p for p in SCENARIOS if p.stem == "slip")
    out = tmp_path / "slip.nwb"
    assert main(["simulate", "--schedule", str(path), "--out", str(out), "--no-progress",
                 "--no-forces"]) == 0
    npz = tmp_path / "slip.npz"
    assert main(["simulate", "--schedule", str(path), "--out", str(npz), "--no-progress",
                 "--no-forces"]) == 0
    truth = np.load(npz)["truth"]
    assert validate(path=str(out)) == []
    assert inspector_findings(out) == []
    with NWBHDF5IO(str(out), "r") as io:
        module = io.read().processing["contact"]
        normal = module["normal_force"]
        assert normal.unit == "N" and np.array_equal(normal.data[:, 0], truth["normal_n"])
        centroid = module["centroid_x"]
        assert centroid.starting_time == 0.0 and centroid.rate == pytest.approx(1000.0)
        assert centroid.unit == "m" and centroid.conversion == 1e-3
        assert np.array_equal(module["slip_state"].data[:, 0], truth["slip"])


def test_train_plays_a_scenario(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (SCENARIOS[0].parent / "press.toml").read_text().replace("hold_s = 0.3",
                                                                    "hold_s = 2.0")
    for i in range(10):  # two conditions in turns while the sphere presses
        name = "0deg_0.5N" if i % 2 else "120deg_0.5N"
        text += f'\n[[event]]\nstart_s = {0.1 + 0.2 * i:.2f}\nstimulus = "{name}"\n'
    path = tmp_path / "train.toml"
    path.write_text(text)
    out = tmp_path / "decoder.npz"
    assert main(["train", "--schedule", str(path), "--out", str(out), "--snr-db", "inf",
                 "--no-progress"]) == 0
    said = capsys.readouterr().out
    assert out.exists() and "of 10 stimuli" in said and "chance 50.0%" in said
    alone = tmp_path / "alone.toml"
    alone.write_text((SCENARIOS[0].parent / "press.toml").read_text())
    assert main(["train", "--schedule", str(alone), "--out", str(out)]) == 2
    assert "no stimuli" in capsys.readouterr().err
