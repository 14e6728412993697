"""NWB output: `simulate --out run.nwb` passes pynwb's validator and holds what the .npz holds."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from pynwb import NWBHDF5IO, validate

REPO = Path(__file__).resolve().parents[1]
ARGS = ["simulate", "--stimulus", "120deg_0.5N", "--snr-db", "10", "--seed", "3",
        "--duration", "0.4", "--no-progress"]


def _skinhil(*args: str, pre: str = "") -> subprocess.CompletedProcess[str]:
    code = f"{pre}import sys; from skinhil.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=300, check=False, env={**os.environ, "PYTHONPATH": str(REPO)})


def test_simulate_nwb_validates_and_equals_the_npz(tmp_path: Path) -> None:
    nwb_path, npz_path = tmp_path / "run.nwb", tmp_path / "run.npz"
    for out in (nwb_path, npz_path):
        res = _skinhil(*ARGS, "--out", str(out))
        assert res.returncode == 0, res.stderr
        assert f"wrote {out}" in res.stdout
    assert validate(path=str(nwb_path)) == []
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
