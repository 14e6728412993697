"""The decoder file: plain data in one ``.npz`` (arrays) with a JSON header, never pickle.

Entries (all plain numeric or Unicode arrays, read with ``allow_pickle=False``):

- ``header``: a 0-d Unicode string holding JSON: ``format`` = ``"skinhil-direction-decoder"``,
  ``format_version`` (:data:`FORMAT_VERSION`), ``feature_spec`` (FeatureSpec.to_dict: window,
  bins, channels, ``dt_s``, ``n_channels``, PSP time constants), ``params`` (C, max_iter,
  tol), ``n_features``, ``n_classes``, ``classes_kind`` (``int``/``str``) and ``sha256``, the
  digest of the rest of the header and of the arrays below, so any change is detected;
- ``coef`` (n_pairs, n_features) float64, ``intercept`` (n_pairs,) float64 (one-vs-one
  hyperplanes, n_pairs = n_classes (n_classes − 1) / 2), ``mean`` and
  ``scale`` (n_features,) float64 — the standardisation — and ``classes`` (n_classes,) int64
  or Unicode.

Each array's ``.npy`` header names its byte order; :func:`save_decoder` writes the machine's
own, and :func:`load_decoder` reads either (a file written on, or converted for, a
big-endian machine holds the same decoder), converting to the machine's order after the
digest (taken over the arrays as stored) is checked.

A file that is not a zip of arrays (e.g. a pickle), lacks an entry, fails the digest, has
another format or version, or does not match the stream, raises :class:`ModelFileError`.
"""

from __future__ import annotations

import hashlib
import json
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from skinhil.decoding.features import FeatureSpec
from skinhil.errors import ConfigError, ModelFileError
from skinhil.output_files import atomic_path

MAX_FILE_BYTES = 128 * 1024 * 1024
"""Largest decoder file (128 MiB) read at all."""
MAX_ARRAY_BYTES = 128 * 1024 * 1024
"""Most bytes its arrays may expand to (128 MiB: the decoder of 9 classes for the largest
skin the wire addresses, 65,535 sensors x 5 bins, holds 95 MiB); checked from the zip
directory and the arrays' headers before anything is decompressed."""
MAX_HEADER_BYTES = 1024 * 1024
"""Largest JSON header entry (1 MiB)."""

FORMAT = "skinhil-direction-decoder"
FORMAT_VERSION = 1
ARRAYS = ("coef", "intercept", "mean", "scale", "classes")


class FittedDecoder(Protocol):
    """What a decoder file holds: the fitted arrays and parameters of a one-vs-one linear SVM
    (:class:`skinhil.decoding.DirectionDecoder` is one; this module knows no class)."""

    C: float
    max_iter: int
    tol: float
    spec_: FeatureSpec
    classes_: np.ndarray
    coef_: np.ndarray
    intercept_: np.ndarray
    mean_: np.ndarray
    scale_: np.ndarray
    n_features_in_: int


@dataclass(frozen=True)
class DecoderFile:
    """The checked content of a decoder file: parameters, feature spec and plain arrays
    (``coef`` (n_pairs, n_features), ``intercept`` (n_pairs,), ``mean`` and ``scale``
    (n_features,) float64, ``classes`` (n_classes,))."""

    spec: FeatureSpec
    C: float
    max_iter: int
    tol: float
    n_features: int
    arrays: dict[str, np.ndarray]


def _digest(arrays: dict[str, np.ndarray], header: dict[str, Any]) -> str:
    h = hashlib.sha256()
    meta = {k: v for k, v in header.items() if k != "sha256"}
    h.update(json.dumps(meta, sort_keys=True).encode())
    for name in ARRAYS:
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_decoder(decoder: FittedDecoder, path: str | Path) -> None:
    """Write a fitted decoder to ``path`` (conventionally ``*.npz``), whole or not at all
    (:func:`skinhil.output_files.atomic_path`)."""
    classes = np.asarray(decoder.classes_)
    if classes.dtype.kind in "iub":
        classes, kind = classes.astype(np.int64), "int"
    elif classes.dtype.kind == "U":
        kind = "str"
    else:
        raise ConfigError(f"class labels of dtype {classes.dtype} cannot be saved as plain "
                          "data; use integer or string labels")
    arrays = {"coef": decoder.coef_, "intercept": decoder.intercept_, "mean": decoder.mean_,
              "scale": decoder.scale_, "classes": classes}
    header = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "feature_spec": decoder.spec_.to_dict(),
        "params": {"C": float(decoder.C), "max_iter": int(decoder.max_iter),
                   "tol": float(decoder.tol), "scheme": "ovo"},
        "n_features": int(decoder.n_features_in_),
        "n_classes": int(classes.size),
        "classes_kind": kind,
    }
    header["sha256"] = _digest(arrays, header)
    p = Path(path)
    try:
        with atomic_path(p) as tmp, tmp.open("wb") as fh:
            entries: dict[str, Any] = {"header": np.array(json.dumps(header, sort_keys=True)),
                                       **arrays}
            np.savez(fh, **entries)
    except OSError as exc:
        raise ModelFileError(f"cannot write decoder file {str(p)!r}: {exc.strerror or exc}") \
            from None


def _member_shape(zf: zipfile.ZipFile, info: zipfile.ZipInfo, where: str) -> None:
    """Refuse an ``.npy`` member whose header is malformed, holds an object (pickle) dtype
    or claims more data than the member holds (e.g. a 10^11-element array): only the
    header is read."""
    fmt = np.lib.format
    try:
        with zf.open(info) as fh:
            version = fmt.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = fmt.read_array_header_1_0(fh)
            else:
                shape, _, dtype = fmt.read_array_header_2_0(fh)
    except (ValueError, SyntaxError, RecursionError, OverflowError, MemoryError, EOFError,
            zipfile.BadZipFile, OSError) as exc:
        raise ModelFileError(f"{where}: entry {info.filename!r} has a malformed array header "
                             f"({type(exc).__name__}) — it is not a decoder file") from None
    if dtype.hasobject:
        raise ModelFileError(f"{where} holds pickled objects; refused (plain data only)")
    n_bytes = math.prod(shape) * dtype.itemsize
    if n_bytes > info.file_size:
        raise ModelFileError(f"{where}: entry {info.filename!r} claims an array of "
                             f"{shape} ({n_bytes} bytes) but holds {info.file_size} bytes — "
                             "the file is corrupted or hostile")


def _check_zip(p: Path, where: str) -> None:
    """Refuse, from the zip directory and the arrays' headers alone, a file that is too big,
    has other entries, or would expand beyond :data:`MAX_ARRAY_BYTES` (a compression
    bomb)."""
    try:
        with zipfile.ZipFile(p) as zf:
            infos = zf.infolist()
            names = sorted(i.filename for i in infos)
            expected = sorted(f"{n}.npy" for n in ("header", *ARRAYS))
            if len(infos) > len(expected) or set(names) - set(expected):
                raise ModelFileError(f"{where} has entries {names[:8]}, not those of a decoder "
                                     f"file ({', '.join(expected)})")
            total = sum(i.file_size for i in infos)
            header = next((i for i in infos if i.filename == "header.npy"), None)
            if total > MAX_ARRAY_BYTES or (header is not None
                                           and header.file_size > MAX_HEADER_BYTES):
                raise ModelFileError(f"{where} expands to {total} bytes — more than a decoder "
                                     f"holds ({MAX_ARRAY_BYTES // 2**20} MiB of arrays, a "
                                     f"{MAX_HEADER_BYTES // 1024} KiB header); refused")
            for info in infos:
                _member_shape(zf, info, where)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, ValueError,
            EOFError) as exc:
        raise ModelFileError(f"{where} is corrupted: {exc}") from None


def _read(p: Path) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    where = f"decoder file {str(p)!r}"
    if not p.is_file():
        raise ModelFileError(f"{where} not found; train one with 'skinhil train'")
    try:
        if p.stat().st_size > MAX_FILE_BYTES:
            raise ModelFileError(f"{where} is larger than {MAX_FILE_BYTES // 2**20} MiB, more "
                                 "than any decoder; refused")
        with p.open("rb") as fh:
            magic = fh.read(4)
    except OSError as exc:
        raise ModelFileError(f"{where} cannot be read: {exc.strerror or exc} — check its "
                             "permissions") from None
    if magic[:1] == b"\x80":
        raise ModelFileError(f"{where} is a pickle; pickled models are refused, save the "
                             "decoder with DirectionDecoder.save")
    if magic != b"PK\x03\x04":
        raise ModelFileError(f"{where} is not a decoder .npz file (wrong magic bytes)")
    _check_zip(p, where)
    try:
        with np.load(p, allow_pickle=False) as data:
            names = set(data.files)
            missing = ({"header", *ARRAYS}) - names
            if missing:
                raise ModelFileError(f"{where} lacks entries {sorted(missing)}; it is not a "
                                     "complete decoder file")
            arrays = {name: np.asarray(data[name]) for name in ARRAYS}
            header_arr = data["header"]
    except ModelFileError:
        raise
    except ValueError as exc:
        if "pickle" in str(exc).lower() or "object arrays" in str(exc).lower():
            raise ModelFileError(f"{where} holds pickled objects; refused (plain data only)") \
                from None
        raise ModelFileError(f"{where} is corrupted: {exc}") from None
    except (zipfile.BadZipFile, OSError, EOFError, KeyError) as exc:
        raise ModelFileError(f"{where} is corrupted: {exc}") from None
    if header_arr.dtype.kind != "U" or header_arr.ndim != 0:
        raise ModelFileError(f"{where} has no readable JSON header")
    try:
        header = json.loads(str(header_arr))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ModelFileError(f"{where} has a corrupted JSON header: "
                             f"{type(exc).__name__}") from None
    if not isinstance(header, dict):
        raise ModelFileError(f"{where} has a JSON header that is not an object")
    return header, arrays


def _native(a: np.ndarray) -> np.ndarray:
    """``a`` in this machine's byte order (the same values)."""
    if a.dtype.byteorder in ("=", "|"):
        return a
    return a.astype(a.dtype.newbyteorder("="))


def load_decoder(path: str | Path) -> DecoderFile:
    """Read and check a decoder file (see module docstring)."""
    p = Path(path)
    where = f"decoder file {str(p)!r}"
    header, arrays = _read(p)
    if header.get("format") != FORMAT:
        raise ModelFileError(f"{where} has format {header.get('format')!r}, not {FORMAT!r}")
    version = header.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(f"{where} has format version {version!r}; this skinhil reads "
                             f"version {FORMAT_VERSION}: retrain with 'skinhil train'")
    if header.get("sha256") != _digest(arrays, header):
        raise ModelFileError(f"{where} is corrupted: its content does not match the stored "
                             "digest")
    arrays = {name: _native(a) for name, a in arrays.items()}
    try:
        spec = FeatureSpec.from_dict(header["feature_spec"])
        params = header["params"]
        if params.get("scheme") != "ovo":
            raise ModelFileError(f"{where} uses decision scheme {params.get('scheme')!r}; "
                                 "this skinhil reads 'ovo'")
        n_features, n_classes = int(header["n_features"]), int(header["n_classes"])
        c, max_iter, tol = float(params["C"]), int(params["max_iter"]), float(params["tol"])
    except (KeyError, TypeError, ValueError, OverflowError, RecursionError, AttributeError) \
            as exc:
        raise ModelFileError(f"{where} has an invalid header ({type(exc).__name__}: "
                             f"{str(exc)[:80]}) — retrain with 'skinhil train'") from None
    if spec.n_steps * spec.n_channels * 8 > MAX_ARRAY_BYTES:
        many = spec.n_channels if spec.n_channels < 10**9 else "over 10^9"
        raise ModelFileError(f"{where}: its feature window ({spec.n_steps} steps x {many} "
                             "channels) would need more than "
                             f"{MAX_ARRAY_BYTES // 2**20} MiB per window — not a decoder of "
                             "this skinhil")
    if n_classes < 2:
        raise ModelFileError(f"{where} holds {n_classes} class(es); a decoder needs two or more")
    n_rows = n_classes * (n_classes - 1) // 2
    shapes = {"coef": (n_rows, n_features), "intercept": (n_rows,), "mean": (n_features,),
              "scale": (n_features,), "classes": (n_classes,)}
    for name, shape in shapes.items():
        if arrays[name].shape != shape:
            raise ModelFileError(f"{where}: array {name!r} has shape {arrays[name].shape}, "
                                 f"expected {shape}")
    if n_features != spec.n_features:
        raise ModelFileError(f"{where}: {n_features} features but its feature spec defines "
                             f"{spec.n_features}")
    for name in ("coef", "intercept", "mean", "scale"):
        if arrays[name].dtype != np.float64:
            raise ModelFileError(f"{where}: array {name!r} holds {arrays[name].dtype}, not "
                                 "float64 — retrain with 'skinhil train'")
        if not np.all(np.isfinite(arrays[name])):
            raise ModelFileError(f"{where}: array {name!r} holds NaN or infinite values — "
                                 "retrain with 'skinhil train'")
    if not np.all(arrays["scale"] > 0):
        raise ModelFileError(f"{where}: its standardisation 'scale' has zero or negative "
                             "entries (features would be divided by them) — retrain with "
                             "'skinhil train'")
    return DecoderFile(spec=spec, C=c, max_iter=max_iter, tol=tol, n_features=n_features,
                       arrays={name: arrays[name] for name in ARRAYS})
