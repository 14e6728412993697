"""Saved decoders: exact round trip; pickles, corruption, mismatches, versions refused."""

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from skinhil.decoding import DirectionDecoder, FeatureSpec
from skinhil.errors import ModelFileError

SPEC = FeatureSpec(dt_s=1e-3, window_s=0.004, bin_s=0.002, n_channels=5)


@pytest.fixture()
def fitted() -> tuple[DirectionDecoder, np.ndarray]:
    rng = np.random.default_rng(0)
    y = np.repeat(np.arange(4), 15)
    x = rng.normal(size=(60, SPEC.n_features)) + y[:, None] * 0.3
    return DirectionDecoder(SPEC, C=0.5).fit(x, y), x


def rewrite(src: Path, dst: Path, **changes: object) -> None:
    with np.load(src, allow_pickle=False) as data:
        entries = {k: data[k] for k in data.files}
    header = json.loads(str(entries["header"]))
    for key, value in changes.items():
        if key in header:
            header[key] = value
        else:
            entries[key] = value
    entries["header"] = np.array(json.dumps(header))
    np.savez(dst, **entries)


def test_round_trip_identical(fitted, tmp_path: Path) -> None:
    dec, x = fitted
    dec.save(tmp_path / "m.npz")
    back = DirectionDecoder.load(tmp_path / "m.npz")
    assert back.spec_ == SPEC and back.C == 0.5
    assert np.array_equal(back.decision_function(x), dec.decision_function(x))
    assert np.array_equal(back.predict(x), dec.predict(x))


def test_pickle_refused(fitted, tmp_path: Path) -> None:
    dec, _ = fitted
    path = tmp_path / "m.pkl"
    path.write_bytes(pickle.dumps(dec))
    with pytest.raises(ModelFileError, match="pickle"):
        DirectionDecoder.load(path)


def test_object_array_refused(fitted, tmp_path: Path) -> None:
    dec, _ = fitted
    dec.save(tmp_path / "m.npz")
    rewrite(tmp_path / "m.npz", tmp_path / "o.npz", classes=np.array([1, "a", None, 2.0],
                                                                       dtype=object))
    with pytest.raises(ModelFileError, match="pickled objects"):
        DirectionDecoder.load(tmp_path / "o.npz")


def test_corruption_refused(fitted, tmp_path: Path) -> None:
    dec, _ = fitted
    path = tmp_path / "m.npz"
    dec.save(path)
    clean = path.read_bytes()
    for needle in (dec.coef_.tobytes()[8:16], '"C": 0.5'.encode("utf-32-le")):
        at = clean.index(needle)  # a byte of the weights, then of the header's JSON
        raw = bytearray(clean)
        raw[at + 1] ^= 0x01
        (tmp_path / "c.npz").write_bytes(bytes(raw))
        with pytest.raises(ModelFileError, match="corrupted"):
            DirectionDecoder.load(tmp_path / "c.npz")
    (tmp_path / "t.npz").write_bytes(path.read_bytes()[:200])
    with pytest.raises(ModelFileError):
        DirectionDecoder.load(tmp_path / "t.npz")
    rewrite(path, tmp_path / "w.npz", coef=dec.coef_ * 1.0001)
    with pytest.raises(ModelFileError, match="digest"):  # arrays changed, digest kept
        DirectionDecoder.load(tmp_path / "w.npz")


def test_version_and_format_refused(fitted, tmp_path: Path) -> None:
    dec, _ = fitted
    dec.save(tmp_path / "m.npz")
    rewrite(tmp_path / "m.npz", tmp_path / "v.npz", format_version=99)
    with pytest.raises(ModelFileError, match="version 99"):
        DirectionDecoder.load(tmp_path / "v.npz")
    rewrite(tmp_path / "m.npz", tmp_path / "f.npz", format="other")
    with pytest.raises(ModelFileError, match="format"):
        DirectionDecoder.load(tmp_path / "f.npz")


def test_mismatched_stream_refused(fitted, tmp_path: Path) -> None:
    dec, _ = fitted
    dec.save(tmp_path / "m.npz")
    with pytest.raises(ModelFileError, match="channels"):
        DirectionDecoder.load(tmp_path / "m.npz", n_channels=338)
    with pytest.raises(ModelFileError, match="dt"):
        DirectionDecoder.load(tmp_path / "m.npz", dt_s=1e-4)
    assert DirectionDecoder.load(tmp_path / "m.npz", n_channels=5, dt_s=1e-3).n_features_in_ \
        == SPEC.n_features


def test_missing_and_foreign_files_refused(tmp_path: Path) -> None:
    with pytest.raises(ModelFileError, match="not found"):
        DirectionDecoder.load(tmp_path / "nope.npz")
    (tmp_path / "x.npz").write_text("hello")
    with pytest.raises(ModelFileError, match="magic"):
        DirectionDecoder.load(tmp_path / "x.npz")
    np.savez(tmp_path / "e.npz", coef=np.zeros(3))
    with pytest.raises(ModelFileError, match="lacks"):
        DirectionDecoder.load(tmp_path / "e.npz")
