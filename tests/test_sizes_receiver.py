"""A decoder trained for a skin size: its features cover that skin's sensors, and the
receiver refuses it for a stream of another size."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from skinhil.errors import ModelFileError
from skinhil.model.geometry import spring_count
from skinhil.receiver.model_file import load_window_decoder
from skinhil.receiver.training import train_decoder


def test_decoder_for_an_8x8_skin(tmp_path: Path) -> None:
    decoder, report = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05,
                                    cross_validation=False, size=(8, 8))
    assert decoder.spec.n_channels == spring_count((8, 8)) == 706
    assert report.decodable_windows >= 2
    path = tmp_path / "d8.npz"
    decoder.save(path)
    assert load_window_decoder(path, n_channels=706).n_channels == 706
    with pytest.raises(ModelFileError, match="expects 706 channels but the stream has 338"):
        load_window_decoder(path, n_channels=spring_count((6, 6)))
