"""``skinhil train``'s model file: exact round trip; refusal of mismatched, corrupted, pickle."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from skinhil.cli import main
from skinhil.errors import ModelFileError
from skinhil.receiver.model_file import load_window_decoder
from skinhil.receiver.training import stream_windows


@pytest.fixture(scope="module")
def model_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "decoder.npz"
    assert main(["train", "--out", str(path), "--snr-db", "inf", "--reps", "5", "--rest",
                 "0.05", "--no-progress"]) == 0
    return path


def test_round_trip_gives_the_same_decisions(model_path):
    a, b = load_window_decoder(model_path), load_window_decoder(model_path)
    x = stream_windows(18, math.inf, 0.05, seed=5).features
    assert x.shape[0] == 18
    xa = a.decoder.decision_function(x)
    assert np.array_equal(xa, b.decoder.decision_function(x))
    assert np.array_equal(a.decoder.predict(x), b.decoder.predict(x))


def test_corrupted_file_is_refused(model_path, tmp_path):
    data = bytearray(model_path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    bad = tmp_path / "bad.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(ModelFileError):
        load_window_decoder(bad)


def test_pickle_is_refused(tmp_path):
    bad = tmp_path / "pickled.npz"
    np.save(bad.with_suffix(".npy"), np.array([{"a": 1}], dtype=object), allow_pickle=True)
    bad.write_bytes(pickle.dumps({"weights": [1, 2, 3]}))
    with pytest.raises(ModelFileError):
        load_window_decoder(bad)


def test_cli_reports_a_bad_model_in_one_line(tmp_path, capsys):
    bad = tmp_path / "x.npz"
    bad.write_bytes(b"not a model")
    assert main(["listen", "--port", "loop://", "--model", str(bad), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("skinhil: error:")
