"""``skinhil simulate`` writes a run numpy reads; bad input is one line and exit status 2."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skinhil import EVENT_DTYPE


def _skinhil(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "skinhil", *args], capture_output=True,
                          text=True, timeout=300)


def test_simulate_writes_forces_and_spikes(tmp_path: Path) -> None:
    out = tmp_path / "run.npz"
    res = _skinhil("simulate", "--stimulus", "B", "--duration", "0.1", "--snr-db", "30",
                   "--out", str(out), "--no-progress")
    assert res.returncode == 0, res.stderr
    with np.load(out, allow_pickle=False) as run:
        assert run["forces_n"].shape == (1000, 338)
        assert run["events"].dtype == EVENT_DTYPE
        assert len(run["events"]) > 0 and np.all(run["events"]["t"] % 100 == 0)
        assert run["markers"]["stimulus_id"].tolist() == [11]
        meta = json.loads(str(run["meta"]))
    assert meta["snr_db"] == 30 and meta["mechanics"] == "geometric"  # auto at 6x6
    assert meta["readout"] == "length"
    assert "wrote" in res.stdout


@pytest.mark.parametrize("args, word", [
    (["--stimulus", "Z"], "unknown stimulus 'Z'"),
    (["--dt", "0"], "--dt"),
    (["--duration", "-1"], "--duration"),
    (["--mechanics", "geometric", "--dt", "0.01"], "too large for the geometric"),
])
def test_bad_input_is_one_line(tmp_path: Path, args: list[str], word: str) -> None:
    res = _skinhil("simulate", "--out", str(tmp_path / "x.npz"), "--no-progress", *args)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skinhil: error:") and word in lines[0]


def test_malformed_schedule(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[[event]]\nstart_s = 0.1\nstimulus = 'nope'\n")
    res = _skinhil("simulate", "--schedule", str(bad), "--out", str(tmp_path / "x.npz"))
    assert res.returncode == 2
    assert res.stderr.strip().splitlines() == [
        res.stderr.strip().splitlines()[0]] and "unknown stimulus 'nope'" in res.stderr
