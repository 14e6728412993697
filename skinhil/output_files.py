"""Output files are written whole or not at all.

Every file skinhil writes (decoders, simulations, recordings, figures, reports) is written to
a temporary file beside its target and renamed over it only when complete: a crash, SIGTERM or
a full disk leaves the previous file intact, never a half-written one. :func:`atomic_path`
is the one way to do it. The file written has the mode a plain ``open()`` would give it,
``0o666`` less the process's umask (a lab's shared folder reads it), not the ``0o600`` of a
temporary file.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

from skinhil.errors import ConfigError


def check_output_path(path: Path, suffixes: tuple[str, ...] = ()) -> Path:
    """``path`` as an absolute path whose folder exists and that is not a folder or device;
    with ``suffixes``, its name ends in one of them (a writer that adds its own suffix would
    write another path than the one named).

    Raises :class:`ConfigError` (one line: what and what to do) otherwise, before any work
    is done, so a long run does not end in an unwritable output.
    """
    path = Path(path).expanduser().absolute()
    if path.is_dir():
        raise ConfigError(f"output '{path}' is a folder — give a file name")
    if suffixes and path.suffix.lower() not in suffixes:
        raise ConfigError(f"output '{path}' does not end in {' or '.join(suffixes)} — name "
                          f"the file with that suffix")
    if path.exists() and not path.is_file():
        raise ConfigError(f"output '{path}' is not a regular file — give a file path")
    if not path.parent.is_dir():
        raise ConfigError(f"output folder '{path.parent}' does not exist — create it first")
    if not os.access(path.parent, os.W_OK):
        raise ConfigError(f"output folder '{path.parent}' is not writable — choose another")
    return path


def check_output_folder(path: Path, what: str) -> Path:
    """``path`` as an absolute path of an output folder that exists and is writable, or that
    can be made: its nearest existing ancestor is a folder this process can write in.

    Raises :class:`ConfigError` (one line naming ``what``, e.g. ``--out``) otherwise, before
    any work is done (a model trained first, then an output refused, is minutes lost).
    """
    path = Path(path).expanduser().absolute()
    probe = path
    while not os.path.lexists(probe) and probe.parent != probe:
        probe = probe.parent
    if not probe.is_dir():
        raise ConfigError(f"{what} '{path}' cannot be created: '{probe}' is not a folder — give "
                          "a folder you can write")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} '{path}' cannot be created: '{probe}' is not writable — give "
                          "a folder you can write")
    return path


def current_umask() -> int:
    """The process's file-creation mask (read from /proc where it can be, so no thread sees
    it changed; else set and restored at once)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on a clean exit, rename it over ``path``.

    The temporary file keeps ``path``'s suffix (writers that choose a format by extension,
    such as numpy's or python-can's, see the right one). On an exception (including
    KeyboardInterrupt and SystemExit) it is removed and ``path`` is left as it was; an
    ``OSError`` of the writer (a full disk, a lost folder) becomes one :class:`ConfigError`.
    The file renamed over ``path`` has mode ``0o666`` less the umask.
    """
    path = check_output_path(path)
    tmp: Path | None = None
    try:
        # the name is kept before the file exists: a stop signal at any instant leaves no
        # file, or one the ``finally`` removes (mkstemp made it before returning its name)
        while tmp is None:
            tmp = path.parent / f".{path.stem}.{secrets.token_hex(4)}.partial{path.suffix}"
            try:
                os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
            except FileExistsError:  # another file's name: not ours to remove
                tmp = None
        yield tmp
        if tmp.exists():
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.chmod(tmp, 0o666 & ~current_umask())
            os.replace(tmp, path)
    except OSError as exc:
        raise ConfigError(f"cannot write '{path}': {exc.strerror or exc} — free some space "
                          "or choose another folder") from None
    finally:
        if tmp is not None:
            tmp.unlink(missing_ok=True)


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_path`; return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)
