"""Hostile decoder files (a compression bomb, array headers of 10^11 elements, JSON nested
100,000 deep, numbers that overflow, a zero in the scale) are refused with ModelFileError
in under 1 s and 200 MB, before anything large is decompressed or allocated."""

from __future__ import annotations

import time
import tracemalloc
from pathlib import Path

import pytest
from harness.hostile_models import HOSTILE, SMALL_SPEC, write_good

from skinhil.decoding import DirectionDecoder
from skinhil.errors import ModelFileError

LIMIT_S = 1.0
LIMIT_BYTES = 200 * 2**20


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_good(tmp_path_factory.mktemp("model") / "good.npz")


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_model_file_refused_fast_and_small(name: str, good: Path,
                                                   tmp_path: Path) -> None:
    make, word = HOSTILE[name]
    path = tmp_path / "hostile.npz"
    make(path, good)
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(ModelFileError, match=word):
            DirectionDecoder.load(path)
        elapsed = time.perf_counter() - t0
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert elapsed < LIMIT_S, (name, elapsed)
    assert peak < LIMIT_BYTES, (name, peak)


def test_good_file_still_loads(good: Path) -> None:
    assert DirectionDecoder.load(good).n_features_in_ == SMALL_SPEC.n_features
