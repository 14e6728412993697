"""Temporary folders that no ended process leaves behind.

A process ended by SIGKILL cannot remove its temporary folder, and its children (which die
with it, :mod:`skinhil.child_processes`) may still be writing into it. So every temporary
folder skinhil makes (``demo``'s score and truth files) is a :class:`TempFolder`: made under
one parent the user owns, ``<the system's temporary folder>/skinhil-<uid>`` (mode 0700), and
named after the process that made it, its pid and its start time (``/proc/<pid>/stat``: a
reused pid is not taken for it). Each new :class:`TempFolder` first removes the folders of
processes that no longer run; a process that ends as it should removes its own. A temporary
file kept beside an output instead (``listen --record``'s event spool, on the output's disk)
is named the same way and removed the same way (:func:`remove_stale` with its prefix).
"""

from __future__ import annotations

import logging
import os
import secrets
import shutil
import stat
import tempfile
import weakref
from pathlib import Path
from types import TracebackType

from skinhil.errors import ConfigError

log = logging.getLogger(__name__)

PARENT_PREFIX = "skinhil-"
"""The parent folder's name before the user id."""


def _start_ticks(pid: int) -> int | None:
    """The start time of process ``pid`` (clock ticks since boot, field 22 of
    ``/proc/<pid>/stat``); None where it is not running or there is no /proc."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
        return int(text[text.rfind(")") + 2:].split()[19])
    except (OSError, ValueError, IndexError):
        return None


def _running(pid: int, ticks: int) -> bool:
    """Whether the process ``pid`` that started at ``ticks`` (0: unknown) still runs."""
    if ticks and Path("/proc/self/stat").exists():
        return _start_ticks(pid) == ticks
    try:  # no /proc, or no start time: the pid alone
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def parent_folder() -> Path:
    """The user's parent of skinhil's temporary folders, made if missing (mode 0700).

    Raises :class:`ConfigError` when that path is not a folder of this user (another user
    made it first, or it is a link): one line naming it and what to do."""
    parent = Path(tempfile.gettempdir()) / f"{PARENT_PREFIX}{os.getuid()}"
    try:
        parent.mkdir(mode=0o700, exist_ok=True)
        st = os.lstat(parent)
    except OSError as exc:
        raise ConfigError(f"cannot make the temporary folder '{parent}': "
                          f"{exc.strerror or exc} — set TMPDIR to a writable folder") from None
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid():
        raise ConfigError(f"'{parent}' is not a folder of this user: remove it, or set TMPDIR "
                          "to another folder")
    return parent


def process_tag() -> str:
    """``PID-START``: this process's pid and start time, the head of the names of the
    temporary files and folders it makes (:func:`ended_process`)."""
    pid = os.getpid()
    return f"{pid}-{_start_ticks(pid) or 0}"


def ended_process(name: str) -> bool:
    """Whether ``name`` begins with the :func:`process_tag` of a process that no longer
    runs (False for a name that begins with no tag)."""
    pid_text, _, rest = name.partition("-")
    ticks_text = rest.partition("-")[0].partition(".")[0]
    if not (pid_text.isdigit() and ticks_text.isdigit()):
        return False
    return not _running(int(pid_text), int(ticks_text))


def remove_stale(parent: Path, prefix: str = "") -> list[Path]:
    """Remove the entries of ``parent`` (files or folders) named ``prefix`` and a
    :func:`process_tag` of a process that no longer runs; return them."""
    removed = []
    for entry in parent.glob(f"{prefix}*"):
        if ended_process(entry.name[len(prefix):]):
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                entry.unlink(missing_ok=True)
            removed.append(entry)
            log.info("removed %s, left by an ended process", entry)
    return removed


class TempFolder:
    """A temporary folder named after this process, under :func:`parent_folder` (see the
    module docstring); the stale folders of ended processes are removed first.

    ``purpose`` (letters, digits, ``-``) ends the folder's name. :attr:`path` is the folder;
    :meth:`cleanup` (or the end of a ``with`` block, or this object's collection, or the
    interpreter's exit) removes it.
    """

    def __init__(self, purpose: str) -> None:
        parent = parent_folder()
        remove_stale(parent)
        self.path = parent / f"{process_tag()}-{purpose}-{secrets.token_hex(4)}"
        """The folder (mode 0700)."""
        self.path.mkdir(mode=0o700)
        self._finalizer = weakref.finalize(self, shutil.rmtree, self.path, True)

    def cleanup(self) -> None:
        """Remove the folder and all it holds."""
        self._finalizer()

    def __enter__(self) -> Path:
        return self.path

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.cleanup()
