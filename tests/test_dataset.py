"""``skinhil dataset`` (skinhil.dataset, docs/dataset.md): a suite's trials on training seeds
in the Spiking Heidelberg Digits' layout, read back with tonic's own SHD reader; a sample's
spikes are those the offline board stream gives for its trial; evaluation seeds are refused;
the reference answerers' fit names only training seeds."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from skinhil.cli import main
from skinhil.dataset import parse_seeds
from skinhil.errors import ConfigError
from skinhil.receiver import task_decoders
from skinhil.receiver.reference_fit import reference_fit
from skinhil.receiver.training import board_stream
from skinhil.suites import SUITES, suite_trials

SUITE = SUITES["tactile-v1"]
SEED = 2
CASES = ("force", "vibration")
WINDOW_S = 0.5  # the board's default response window
N_SENSORS = 338


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("dataset") / "Tactile" / "train.h5"
    out.parent.mkdir()
    assert main(["dataset", "--suite", "tactile-v1", "--seeds", str(SEED), "--cases",
                 ",".join(CASES), "--out", str(out), "--no-progress"]) == 0
    return out


def test_layout(written: Path) -> None:
    with h5py.File(written, "r") as f:
        times, units, labels = f["spikes/times"], f["spikes/units"], f["labels"][()]
        extra = f["extra"]
        n = len(labels)
        keys = [k.decode() for k in extra["keys"][()]]
        assert keys == ["vibration:50", "vibration:100", "vibration:200", "vibration:300"]
        assert len(times) == len(units) == n
        for name in ("seed", "speaker", "case", "task", "trial", "start_s", "duration_s",
                     "x_mm", "y_mm", "force_n", "frequency_hz", "slip_onset_s"):
            assert extra[name].shape == (n,), name
        assert set(extra["seed"][()]) == set(extra["speaker"][()]) == {SEED}
        cases = [c.decode() for c in extra["case_names"][()]]
        case = np.array([cases[i] for i in extra["case"][()]])
        trials = {c: SUITE.case(c).trials for c in CASES}
        for c in CASES:  # every press and every vibration of the run is a sample
            assert np.sum(case == c) == trials[c]
        for i in range(n):
            t, u = times[i], units[i]
            assert len(t) == len(u) > 0
            assert np.all(np.diff(t) >= 0) and t[0] >= 0
            assert t[-1] < extra["duration_s"][i] == pytest.approx(WINDOW_S)
            assert u.max() < N_SENSORS
        force = case == "force"
        assert np.all(labels[force] == -1)
        hz = extra["frequency_hz"][()]
        assert [keys[k] for k in labels[~force]] == [f"vibration:{f:g}" for f in hz[~force]]
        assert np.all((extra["force_n"][force] > 0.15) & (extra["force_n"][force] < 0.85))
        assert np.all(np.isnan(extra["slip_onset_s"][()]))
        place = extra["units"]
        assert place["x_m"].shape == place["layer"].shape == (N_SENSORS,)
        assert place["spring"].shape == (N_SENSORS, 2)
        assert set(place["layer"][()]) == {1, 2, 3, 12, 23}
        assert f.attrs["suite"] == "tactile-v1" and f.attrs["suite_version"] == 1
        assert list(f.attrs["seeds"]) == [SEED]


def test_tonic_reads_it(written: Path) -> None:
    from tonic.datasets.hsd import HSD  # tonic's own SHD reader

    class Tactile(HSD):  # type: ignore[misc]
        data_filename = "train.h5"

    data = Tactile(str(written.parent.parent))
    with h5py.File(written, "r") as f:
        assert len(data) == len(f["labels"])
        events, target = data[len(data) - 1]
        assert target == f["labels"][-1]
        assert np.array_equal(events["x"], f["spikes/units"][-1])
        # tonic casts s * 1e6 to int µs by truncation: a time may read 1 µs early
        assert np.all(np.abs(events["t"] - f["spikes/times"][-1] * 1e6) < 1)


def test_samples_are_the_board_streams_spikes(written: Path) -> None:
    """Each force sample holds exactly the spikes the board's offline stream
    (skinhil.receiver.training.board_stream: serve --suite's sensor, seed and scene) gives
    in its window, and starts at its press's touch-down."""
    trials = suite_trials("tactile-v1:force", SEED)
    scene = trials.scenario.scene
    assert scene is not None
    ev = np.concatenate([e for e, _, _ in board_stream(
        trials.duration_s + WINDOW_S, 10.0, 0.0, SEED, schedule=trials.scenario.schedule,
        scene=scene)])
    with h5py.File(written, "r") as f:
        cases = [c.decode() for c in f["extra/case_names"][()]]
        rows = [i for i, c in enumerate(f["extra/case"][()]) if cases[c] == "force"]
        starts = f["extra/start_s"][rows]
        for i, start_s in zip(rows, starts, strict=True):
            lo = int(round(start_s * 1e6))
            sel = ev[(ev["t"] >= lo) & (ev["t"] < lo + int(WINDOW_S * 1e6))]
            got_t = np.round(f["spikes/times"][i] * 1e6).astype(np.int64) + lo
            assert np.array_equal(got_t, sel["t"])
            assert np.array_equal(f["spikes/units"][i], sel["addr"])
    presses = np.sort([c.start_s for c in scene.contacts])
    lag = np.sort(starts) - presses  # the sphere's way down before it touches
    assert np.all((lag >= 0) & (lag < 0.05))


def test_evaluation_seeds_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x.h5"
    first_eval = SUITE.evaluation_seeds.start
    status = main(["dataset", "--suite", "tactile-v1", "--seeds",
                   f"{first_eval - 1}-{first_eval}", "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert status == 2 and not out.exists()
    assert len(err.splitlines()) == 1
    assert f"seed {first_eval} is not a training seed of tactile-v1" in err


def test_parse_seeds() -> None:
    assert parse_seeds("1-3,7,2") == [1, 2, 3, 7]
    for bad in ("a", "5-2", "-1", "1-"):
        with pytest.raises(ConfigError):
            parse_seeds(bad)


def test_reference_fit_names_training_seeds_only() -> None:
    fit = reference_fit()
    suite = SUITES[fit["suite"]]
    assert suite.version == fit["suite_version"]
    assert fit["seeds"] and all(s in suite.training_seeds for s in fit["seeds"])
    assert "fit_reference_answerers.py" in fit["command"]
    assert task_decoders.FORCE_OFFSET_N == fit["force"]["offset_n"]
    assert task_decoders.SLIP_CHANNELS == tuple(fit["slip"]["channels"])
    assert task_decoders.VIBRATION_MEANS == tuple(map(tuple, fit["vibration"]["means"]))
