"""Hostile decoder files, built from a good one: what an attacker (or a broken disk) could
hand to ``--model``. Each builder writes ``path`` from the good file ``good``."""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from skinhil.decoding import DirectionDecoder, FeatureSpec
from skinhil.decoding.model_file import MAX_ARRAY_BYTES, _digest

SMALL_SPEC = FeatureSpec(dt_s=1e-3, window_s=0.004, bin_s=0.002, n_channels=5)
"""A decoder of 5 channels: of no skin's size."""


def write_good(path: Path, n_channels: int = SMALL_SPEC.n_channels) -> Path:
    """A valid decoder file of :data:`SMALL_SPEC` (with ``n_channels``) at ``path``."""
    spec = FeatureSpec(dt_s=SMALL_SPEC.dt_s, window_s=SMALL_SPEC.window_s,
                       bin_s=SMALL_SPEC.bin_s, n_channels=n_channels)
    rng = np.random.default_rng(0)
    y = np.repeat(np.arange(3), 10)
    x = rng.normal(size=(30, spec.n_features)) + y[:, None]
    DirectionDecoder(spec).fit(x, y).save(path)
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


def bomb(path: Path, good: Path) -> None:
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


def huge_header(path: Path, good: Path) -> None:
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


def deep_json(path: Path, good: Path) -> None:
    _, arrays = _entries(good)
    _write(path, "[" * 100_000 + "]" * 100_000, arrays)


def overflow(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    header["n_features"] = float("inf")  # JSON 'Infinity': int() of it overflows
    _write(path, _signed(header, arrays), arrays)


def huge_int(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    header["feature_spec"]["n_channels"] = 10**400
    _write(path, _signed(header, arrays), arrays)


def zero_scale(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    arrays["scale"][0] = 0.0
    _write(path, _signed(header, arrays), arrays)


def extra_entry(path: Path, good: Path) -> None:
    header, arrays = _entries(good)
    _write(path, _signed(header, arrays), {**arrays, "payload": np.zeros(4)})


HOSTILE: dict[str, tuple[Callable[[Path, Path], None], str]] = {
    "compression bomb": (bomb, "expands to"),
    "10^11-element header": (huge_header, "claims an array"),
    "JSON nested 100000 deep": (deep_json, "RecursionError"),
    "n_features = Infinity": (overflow, "OverflowError"),
    "n_channels = 10^400": (huge_int, "feature window"),
    "zero in the scale": (zero_scale, "scale"),
    "an extra entry": (extra_entry, "entries"),
}


"""Each hostile file's builder and a word of its refusal."""


def pickled(path: Path, good: Path) -> None:
    """A pickle where the decoder file should be (it must never be unpickled)."""
    import pickle

    path.write_bytes(pickle.dumps({"coef": [1.0]}))
