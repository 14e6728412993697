"""Hostile decoder files (a compression bomb, array headers of 10^11 elements, JSON nested
100,000 deep, numbers that overflow, a zero in the scale) are refused with ModelFileError
in under 1 s and 200 MB, before anything large is decompressed or allocated."""

from __future__ import annotations

import io
import json
import time
import tracemalloc
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from skinhil.decoding import DirectionDecoder, FeatureSpec
from skinhil.decoding.model_file import MAX_ARRAY_BYTES, _digest
from skinhil.errors import ModelFileError

SPEC = FeatureSpec(dt_s=1e-3, window_s=0.004, bin_s=0.002, n_channels=5)
LIMIT_S = 1.0
LIMIT_BYTES = 200 * 2**20


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rng = np.random.default_rng(0)
    y = np.repeat(np.arange(3), 10)
    x = rng.normal(size=(30, SPEC.n_features)) + y[:, None]
    path = tmp_path_factory.mktemp("model") / "good.npz"
    DirectionDecoder(SPEC).fit(x, y).save(path)
    return path


def _entries(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    return json.loads(str(arrays.pop("header"))), arrays


def _write(path: Path, header_text: str, arrays: dict[str, np.ndarray]) -> None:
    np.savez(path, header=np.array(header_text), **arrays)


def _signed(header: dict, arrays: dict[str, np.ndarray]) -> str:
    """The header with a valid digest: an attacker can compute it, it is no secret."""
    header = dict(header, sha256=_digest(arrays, header))
    return json.dumps(header)


def _bomb(path: Path, good: Path) -> None:
    """A 40-million-float64 'coef' (320 MB of zeros) deflated to a few hundred KB."""
    header, arrays = _entries(good)
    n = 40_000_000
    assert n * 8 > MAX_ARRAY_BYTES
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("header.npy", _npy(np.array(json.dumps(header))))
        for name, arr in arrays.items():
            if name != "coef":
                zf.writestr(f"{name}.npy", _npy(arr))
        with zf.open("coef.npy", "w", force_zip64=True) as fh:
            np.lib.format.write_array_header_1_0(
                fh, {"descr": "<f8", "fortran_order": False, "shape": (n,)})
            chunk = bytes(1 << 24)
            for _ in range(n * 8 // len(chunk)):
                fh.write(chunk)
            fh.write(bytes(n * 8 % len(chunk)))


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, allow_pickle=False)
    return buf.getvalue()


def _huge_header(path: Path, good: Path) -> None:
    """'coef' whose .npy header claims 10^11 float64s (800 GB) over 64 bytes of data."""
    header, arrays = _entries(good)
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("header.npy", _npy(np.array(json.dumps(header))))
        for name, arr in arrays.items():
            if name == "coef":
                buf = io.BytesIO()
                np.lib.format.write_array_header_1_0(
                    buf, {"descr": "<f8", "fortran_order": False, "shape": (10**5, 10**6)})
                zf.writestr("coef.npy", buf.getvalue() + bytes(64))
            else:
                zf.writestr(f"{name}.npy", _npy(arr))


def _deep_json(path: Path, good: Path) -> None:
    _, arrays = _entries(good)
    _write(path, "[" * 100_000 + "]" * 100_000, arrays)


def _overflow(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    header["n_features"] = float("inf")  # JSON 'Infinity': int() of it overflows
    _write(path, _signed(header, arrays), arrays)


def _huge_int(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    header["feature_spec"]["n_channels"] = 10**400
    _write(path, _signed(header, arrays), arrays)


def _zero_scale(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    arrays["scale"][0] = 0.0
    _write(path, _signed(header, arrays), arrays)


def _extra_entry(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    _write(path, _signed(header, arrays), {**arrays, "payload": np.zeros(4)})


HOSTILE: dict[str, tuple[Callable[[Path, Path], None], str]] = {
    "compression bomb": (_bomb, "expands to"),
    "10^11-element header": (_huge_header, "claims an array"),
    "JSON nested 100000 deep": (_deep_json, "RecursionError"),
    "n_features = Infinity": (_overflow, "OverflowError"),
    "n_channels = 10^400": (_huge_int, "feature window"),
    "zero in the scale": (_zero_scale, "scale"),
    "an extra entry": (_extra_entry, "entries"),
}


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
    assert DirectionDecoder.load(good).n_features_in_ == SPEC.n_features
