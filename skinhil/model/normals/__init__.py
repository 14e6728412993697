"""The neurons' standard normals from the compiled C kernel (``_kernel.c`` beside this file).

:func:`fill_normals` gives the pair of float32 standard normals of every channel at one step,
a pure function of the channel's key and the step (the definition: :mod:`skinhil.model.rng`).
Compiled kernels call the same C function through :data:`normals_ext`, a named external
symbol (``skinhil_normals``, registered with LLVM when this module is imported), so numba's
cache keeps working across processes.

The C kernel has three paths that give bit-identical normals: ``avx512`` (16 lanes), ``avx2``
(8 lanes, with FMA) and ``portable`` (C). The widest one the CPU runs is used, unless the
environment variable ``SKINHIL_NORMALS_PATH`` names one when this module is imported;
:func:`normals_path` says which is in use.
"""

from __future__ import annotations

import ctypes
import importlib.util
import os
from typing import Any

import llvmlite.binding
import numba
import numpy as np
from numba import types

from skinhil.errors import ConfigError, SkinhilError

PATHS = ("portable", "avx2", "avx512")
"""The kernel's paths, by the number the C library knows them by."""
PATH_ENV = "SKINHIL_NORMALS_PATH"
"""The environment variable that forces a path (read when this module is imported)."""
SYMBOL = "skinhil_normals"
"""The C function compiled kernels call: ``void skinhil_normals(const uint64_t *keys,
int64_t n, int64_t step, float *z1, float *z2)``."""


def _library() -> ctypes.CDLL:
    spec = importlib.util.find_spec(f"{__name__}._kernel")
    if spec is None or spec.origin is None:
        raise SkinhilError("skinhil's normals kernel (skinhil.model.normals._kernel) is not "
                           "built: reinstall skinhil (pip install .), or in a source checkout "
                           "run python setup.py build_ext --inplace")
    return ctypes.CDLL(spec.origin)


def _choose(lib: ctypes.CDLL, forced: str | None) -> str:
    lib.skinhil_normals_use.argtypes = [ctypes.c_int]
    lib.skinhil_normals_use.restype = ctypes.c_int
    if not forced:
        return PATHS[lib.skinhil_normals_use(-1)]
    if forced not in PATHS:
        raise ConfigError(f"{PATH_ENV}={forced!r} is not a path of the normals kernel: "
                          f"use one of {', '.join(PATHS)}, or unset it")
    if lib.skinhil_normals_use(PATHS.index(forced)) < 0:
        raise ConfigError(f"{PATH_ENV}={forced}: this CPU does not run that path: use "
                          f"{', '.join(p for p in PATHS if _supported(lib, p))}, or unset it")
    return forced


def _supported(lib: ctypes.CDLL, path: str) -> bool:
    lib.skinhil_normals_supported.argtypes = [ctypes.c_int]
    lib.skinhil_normals_supported.restype = ctypes.c_int
    return bool(lib.skinhil_normals_supported(PATHS.index(path)))


_LIB = _library()
_PATH = _choose(_LIB, os.environ.get(PATH_ENV))
llvmlite.binding.add_symbol(SYMBOL, ctypes.cast(_LIB.skinhil_normals, ctypes.c_void_p).value)

normals_ext: Any = types.ExternalFunction(  # called from compiled code only
    SYMBOL, types.void(types.CPointer(types.uint64), types.int64, types.int64,
                       types.CPointer(types.float32), types.CPointer(types.float32)))
"""The C function as numba sees it: call ``normals_ext(keys.ctypes, n, step, z1.ctypes,
z2.ctypes)`` from compiled code (contiguous arrays, ``z1`` and ``z2`` float32)."""


def normals_path() -> str:
    """The path of the normals kernel in use: ``"avx512"``, ``"avx2"`` or ``"portable"``."""
    return _PATH


def supported_paths() -> tuple[str, ...]:
    """The paths this CPU runs (``"portable"`` always)."""
    return tuple(p for p in PATHS if _supported(_LIB, p))


@numba.njit(cache=True, nogil=True)
def fill_normals(keys: np.ndarray, step: int, z1: np.ndarray,
                 z2: np.ndarray) -> None:  # pragma: no cover - compiled
    """``z1[i], z2[i]``: the pair of float32 standard normals of the channel with ``keys[i]``
    (contiguous uint64) at ``step`` (0, 1, ...); ``z1``, ``z2`` contiguous float32 of at least
    ``len(keys)``."""
    normals_ext(keys.ctypes, keys.shape[0], step, z1.ctypes, z2.ctypes)
