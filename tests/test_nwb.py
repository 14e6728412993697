"""NWB output: `simulate --out run.nwb` passes pynwb's validator and holds what the .npz holds."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from pynwb import NWBHDF5IO, validate

BAD = ("CRITICAL", "BEST_PRACTICE_VIOLATION")
"""nwbinspector's findings DANDI refuses a file for (suggestions are allowed)."""


def inspector_findings(path: Path) -> list[str]:
    """nwbinspector's CRITICAL and BEST_PRACTICE_VIOLATION findings on ``path``."""
    from nwbinspector import inspect_nwbfile

    return [f"{m.importance.name}: {m.check_function_name}: {m.message}"
            for m in inspect_nwbfile(nwbfile_path=str(path)) if m.importance.name in BAD]

REPO = Path(__file__).resolve().parents[1]
ARGS = ["simulate", "--stimulus", "120deg_0.5N", "--snr-db", "10", "--seed", "3",
        "--duration", "0.4", "--no-progress"]


def _skinhil(*args: str, pre: str = "") -> subprocess.CompletedProcess[str]:
    code = f"{pre}import sys; from skinhil.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=300, check=False, env={**os.environ, "PYTHONPATH": str(REPO)})


def test_simulate_nwb_validates_and_equals_the_npz(tmp_path: Path) -> None:
    """The NWB file validates, nwbinspector finds nothing DANDI refuses, the metadata
    options land in it, it holds what the .npz holds, and both follow the umask."""
    import datetime

    nwb_path, npz_path = tmp_path / "run.nwb", tmp_path / "run.npz"
    before = datetime.datetime.now(datetime.UTC)
    for out, extra in ((nwb_path, ["--experimenter", "Doe, Jane", "--keywords", "a,b c",
                                   "--institution", "Lab U"]), (npz_path, [])):
        res = _skinhil(*ARGS, "--out", str(out), *extra, pre="import os; os.umask(0o027); ")
        assert res.returncode == 0, res.stderr
        assert f"wrote {out}" in res.stdout
        assert oct(out.stat().st_mode & 0o777) == oct(0o640), out  # 0o666 less the umask
    assert validate(path=str(nwb_path)) == []
    assert inspector_findings(nwb_path) == []
    ref = np.load(npz_path)
    events, forces = ref["events"], ref["forces_n"]
    assert len(events) > 0
    with NWBHDF5IO(str(nwb_path), "r") as io:
        nwb = io.read()
        units = nwb.units.to_dataframe()
        assert list(units["spring"]) == list(range(forces.shape[1]))
        for s in np.unique(events["addr"]):
            want = np.sort(events["t"][events["addr"] == s]) * 1e-6
            np.testing.assert_allclose(units["spike_times"].iloc[int(s)], want, atol=1e-12)
        assert sum(len(t) for t in units["spike_times"]) == len(events)
        trials = nwb.trials.to_dataframe()
        assert list(trials["stimulus"]) == ["120deg_0.5N"]
        assert abs(trials["force_n"].iloc[0] - 0.5) < 1e-9
        assert abs(trials["angle_deg"].iloc[0] - 120.0) < 1e-6
        assert list(nwb.experimenter) == ["Doe, Jane"] and list(nwb.keywords) == ["a", "b c"]
        assert nwb.institution == "Lab U" and nwb.subject.subject_id == "skinhil-skin-6x6"
        assert before <= nwb.session_start_time <= datetime.datetime.now(datetime.UTC)
        assert nwb.units.resolution == 1e-4
        assert "skinhil_board" in nwb.devices
        # sensor 0 joins M1 and M2 of the top layer: its midpoint lies there, z = 0
        row = units.iloc[0]
        assert row["z_m"] == 0.0 and row["x_m"] < 0 < row["y_m"]
        ts = nwb.acquisition["spring_forces"]
        assert ts.unit == "N" and abs(ts.rate - 1e4) < 1e-6
        np.testing.assert_array_equal(ts.data[:], forces)


def test_nwb_without_pynwb_is_one_error_line(tmp_path: Path) -> None:
    res = _skinhil(*ARGS, "--out", str(tmp_path / "run.nwb"),
                   pre="import sys; sys.modules['pynwb'] = None; ")
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skinhil: error:")
    assert 'pip install "skinhil[nwb]"' in lines[0]
    assert not (tmp_path / "run.nwb").exists()


def test_listen_record_nwb_validates_and_holds_the_session(tmp_path: Path) -> None:
    """A board on a pty, `listen --record session.nwb` on the other end: the file validates,
    its spikes are the events the board generated, its trials the board's stimuli."""
    import json
    import math
    import shutil
    import time

    import pytest
    from harness.serve import RUN_DIR, ServeProcess, serve_env

    from skinhil.decoding.model_file import save_decoder
    from skinhil.process_output import SUMMARY, last_record, records
    from skinhil.receiver.training import train_decoder

    if shutil.which("socat") is None:
        pytest.skip("socat is not installed (apt-get install socat)")
    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False)
    model = tmp_path / "model.npz"
    save_decoder(decoder, model)
    board_end, host_end = tmp_path / "ttyBOARD", tmp_path / "ttyHOST"
    socat = subprocess.Popen(["socat", f"pty,raw,echo=0,link={board_end}",
                              f"pty,raw,echo=0,link={host_end}"])
    session = tmp_path / "session.nwb"
    board = None
    try:
        end = time.monotonic() + 10
        while not (board_end.exists() and host_end.exists()):
            assert time.monotonic() < end, "socat made no pty pair"
            time.sleep(0.05)
        listen = subprocess.Popen(
            [sys.executable, "-m", "skinhil", "listen", "--port", str(host_end), "--model",
             str(model), "--json", "--record", str(session)],
            cwd=RUN_DIR, env=serve_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True)
        assert listen.stdout is not None
        ready = json.loads(listen.stdout.readline())  # its first line, once the link is open
        assert ready["type"] == "ready" and ready["command"] == "listen", ready
        board = ServeProcess("--port", str(board_end), "--duration", "3", "--seed", "1",
                             "--snr-db", "10", "--json")
        assert board.wait(120) == 0, board.stderr
        out, err = listen.communicate(timeout=60)  # it ends at the board's RUN_END record
        assert listen.returncode == 0, err
    finally:
        if board is not None:
            board.kill()
        socat.kill()
    generated = board.summary()["generated"]
    info = last_record(records(out), SUMMARY)
    assert info is not None, out
    assert info["link"]["events_decoded"] == generated > 0
    assert info["run_end"] == {"t_s": 3.0, "reason": "DURATION"}
    assert validate(path=str(session)) == []
    assert inspector_findings(session) == []
    with NWBHDF5IO(str(session), "r") as io:
        nwb = io.read()
        # the session starts when the board did (board time 0 on the wall clock), not
        # when the file was written
        start = nwb.session_start_time.timestamp()
        assert abs(start - board.start_wall_s()) < 1.0, (start, board.start_wall_s())
        assert nwb.units.resolution == 1e-4
        units = nwb.units.to_dataframe()
        assert len(units) == 338
        assert sum(len(t) for t in units["spike_times"]) == generated
        assert nwb.trials is not None, out[-2000:]
        trials = nwb.trials.to_dataframe()
        assert len(trials) >= 3
        assert (trials["stop_time"] > trials["start_time"]).all()
        assert set(trials["stimulus_id"]) <= set(range(9))
        assert "decisions" in nwb.intervals
