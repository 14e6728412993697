"""Where numba caches the compiled kernels: one directory per version of the sources.

numba keys a cached kernel on its own source file only (that file's modification time and
size). A kernel that calls or inlines kernels of other files — ``skinhil.model.sensor``'s fused
kernels run those of ``mechanics_linear``, ``neurons``, ``stimuli`` and ``rng`` — would keep
running the old callee after that other file changed. So, before any kernel is defined,
:func:`configure` points numba's cache at ``<base>/<hash>``, ``<hash>`` a digest of every
source file of the packages that hold kernels (:data:`KERNEL_PACKAGES`): an edit anywhere in
them selects a fresh, empty cache directory, and every kernel compiles again from the
current sources. ``<base>`` is ``$NUMBA_CACHE_DIR`` when set, else
``skinhil/__pycache__/numba`` next to the sources (``protocols/__pycache__/numba`` in a copy of
``protocols`` alone) (so a checkout, and a user-mode Linux guest
that mounts it, find its cache without any environment); when that folder cannot be written
(a read-only site-packages) the user's cache folder, ``$XDG_CACHE_HOME/skinhil/numba`` or
``~/.cache/skinhil/numba``, and the log says which at INFO. Only the
:data:`KEEP_VERSIONS` most recently used directories are kept.

Importing this module configures the cache (:data:`CACHE_DIR`); ``protocols/__init__.py``
imports it first of all (the wire codecs stand alone: they need nothing of ``skinhil``);
``skinhil`` and ``firmware_sim`` import it before they define a kernel.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
from pathlib import Path

import numba

log = logging.getLogger(__name__)

KERNEL_PACKAGES: tuple[str, ...] = ("skinhil", "protocols", "firmware_sim")
"""The packages whose sources key the cache (all of them define or call numba kernels)."""

KEEP_VERSIONS = 4
"""Cache directories of other source versions kept (most recently used first)."""

_ROOT = Path(__file__).resolve().parents[1]


def source_files(root: Path = _ROOT) -> list[Path]:
    """Every ``.py`` file of :data:`KERNEL_PACKAGES` under ``root``, in a fixed order."""
    files: list[Path] = []
    for name in KERNEL_PACKAGES:
        package = root / name
        if package.is_dir():
            files += [p for p in package.rglob("*.py") if "__pycache__" not in p.parts]
    return sorted(files, key=lambda p: p.relative_to(root).as_posix())


def source_hash(root: Path = _ROOT) -> str:
    """SHA-256 (first 16 hex digits) over the path and content of every :func:`source_files`."""
    digest = hashlib.sha256()
    for path in source_files(root):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()[:16]


def cache_base() -> Path:
    """The directory holding one cache directory per source version (see module docstring)."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        return Path(user)
    home = "skinhil" if (_ROOT / "skinhil").is_dir() else "protocols"
    return _ROOT / home / "__pycache__" / "numba"


def user_cache_base() -> Path:
    """The user's cache folder for kernels: ``$XDG_CACHE_HOME/skinhil/numba`` or
    ``~/.cache/skinhil/numba``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "skinhil" / "numba"


def _claim(base: Path, version: str) -> Path | None:
    """``base/version`` made, marked most recently used and writable, the older versions
    pruned; None when it cannot be written."""
    path = base / version
    try:
        path.mkdir(parents=True, exist_ok=True)
        os.utime(path)  # marks it most recently used
        if not os.access(path, os.W_OK | os.X_OK):
            raise PermissionError(f"{path} is not writable")
        _prune(base, keep=path)
    except OSError as exc:
        log.debug("kernel cache %s not writable: %s", path, exc)
        return None
    return path


def configure() -> Path:
    """Point numba's kernel cache at this source version's directory and return it: under
    :func:`cache_base`, else under :func:`user_cache_base` when that cannot be written
    (logged at INFO); when neither can, the first, and numba compiles without caching."""
    version = source_hash()
    path = _claim(cache_base(), version)
    if path is None and not os.environ.get("NUMBA_CACHE_DIR"):
        path = _claim(user_cache_base(), version)
        if path is not None:
            log.info("kernel cache: %s (the package folder %s cannot be written)", path,
                     cache_base())
    if path is None:  # numba then compiles without caching; skinhil compile says so
        path = cache_base() / version
    numba.config.CACHE_DIR = str(path)  # type: ignore[attr-defined]  # set at run time
    return path


def _prune(base: Path, keep: Path) -> None:
    """Remove the cache directories of source versions beyond the :data:`KEEP_VERSIONS` most
    recently used (``keep`` is never removed)."""
    others = [p for p in base.iterdir()
              if p.is_dir() and p != keep and len(p.name) == 16
              and all(c in "0123456789abcdef" for c in p.name)]
    others.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    for old in others[KEEP_VERSIONS:]:
        shutil.rmtree(old, ignore_errors=True)


CACHE_DIR = configure()
"""This process's kernel cache directory."""
