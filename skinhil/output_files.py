"""Output files are written whole or not at all.

Every file skinhil writes (decoders, simulations, recordings, figures, reports) is written to
a temporary file beside its target and renamed over it only when complete: a crash, SIGTERM or
a full disk leaves the previous file intact, never a half-written one. :func:`atomic_path`
is the one way to do it.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from skinhil.errors import ConfigError


def check_output_path(path: Path) -> Path:
    """``path`` as an absolute path whose folder exists and that is not a folder or device.

    Raises :class:`ConfigError` (one line: what and what to do) otherwise, before any work
    is done, so a long run does not end in an unwritable output.
    """
    path = Path(path).expanduser().absolute()
    if path.is_dir():
        raise ConfigError(f"output '{path}' is a folder: give a file name")
    if path.exists() and not path.is_file():
        raise ConfigError(f"output '{path}' is not a regular file: give a file path")
    if not path.parent.is_dir():
        raise ConfigError(f"output folder '{path.parent}' does not exist: create it first")
    if not os.access(path.parent, os.W_OK):
        raise ConfigError(f"output folder '{path.parent}' is not writable: choose another")
    return path


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on a clean exit, rename it over ``path``.

    The temporary file keeps ``path``'s suffix (writers that choose a format by extension,
    such as numpy's or python-can's, see the right one). On an exception (including
    KeyboardInterrupt and SystemExit) it is removed and ``path`` is left as it was.
    """
    path = check_output_path(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}",
                                dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        if tmp.exists():
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
