"""The held object's truth as a file that grows during the run: the board appends its
records (:data:`skinhil.plant.HELD_DTYPE`, little-endian) as it runs, another process tails
it (the grasp demo's live view). Never on the decoder's link.

The file opens with :data:`MAGIC` (16 bytes: the format and its record size), then the
records. A run appends to a file that starts with :data:`MAGIC` (a stopped run's records stay
in it), starts a new one where there is none (or an empty file), and refuses any other file
before the board starts (:func:`check_truth_path`): it is never truncated or overwritten.
A write that fails (a full disk) is cut back to the last whole record and the run goes on
without the file (its score and its closing records are worth more than the truth), so the
file never holds part of a record; the writer keeps the error (:attr:`HeldTruthWriter.error`)
for the run to report as it ends.
"""

from __future__ import annotations

import contextlib
import logging
import os
from pathlib import Path

import numpy as np

from skinhil.errors import ConfigError
from skinhil.output_files import check_output_path
from skinhil.plant.truth import HELD_DTYPE

log = logging.getLogger(__name__)

FLUSH_RECORDS = 50
"""Records buffered before a write (50 ticks: 50 ms of 1 ms ticks)."""
MAGIC = b"skinhil held %2d\n" % HELD_DTYPE.itemsize
"""The first 16 bytes of a held-object truth file: its format and its record size (bytes)."""


def _is_truth_file(path: Path) -> bool:
    """Whether ``path`` is empty or starts with :data:`MAGIC`."""
    with path.open("rb") as f:
        head = f.read(len(MAGIC))
    return head in (b"", MAGIC)


def check_truth_path(path: Path) -> Path:
    """``path`` as an absolute path a held-object truth file can be appended to: a new file
    in a writable folder, an empty file, or a truth file skinhil wrote, writable. Raises
    :class:`ConfigError` (one line) otherwise, before any work is done."""
    path = check_output_path(path)
    if not path.exists():
        return path
    try:
        ours = _is_truth_file(path)
    except OSError as exc:
        raise ConfigError(f"cannot read '{path}': {exc.strerror or exc} — give a new file "
                          "name for the held object's truth") from None
    if not ours:
        raise ConfigError(f"'{path}' exists and is not a held-object truth file (it is never "
                          "overwritten) — give a new file name, or remove it first")
    if not os.access(path, os.W_OK):
        raise ConfigError(f"'{path}' is read-only — make it writable, or give a new file "
                          "name")
    return path


class HeldTruthWriter:
    """Appends held-object records to ``path`` (see the module docstring: a file it wrote,
    or a new one), written and flushed every :data:`FLUSH_RECORDS` records and at
    :meth:`close`. Raises :class:`ConfigError` when ``path`` cannot be opened or is another
    kind of file."""

    def __init__(self, path: Path) -> None:
        self.path = check_truth_path(path)
        self._rows: list[bytes] = []
        self.records = 0
        """Records written so far (by this writer)."""
        self._fd: int | None = None
        self.error: OSError | None = None
        """The write error that ended the file (a full disk), None while it is written."""
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        except OSError as exc:
            raise ConfigError(f"cannot write '{self.path}': {exc.strerror or exc} — choose "
                              "another file") from None
        self._fd = fd
        self._good = os.lseek(fd, 0, os.SEEK_END)
        """Size (bytes) of the file's whole part: where a failed write is cut back to."""
        torn = (self._good - len(MAGIC)) % HELD_DTYPE.itemsize if self._good else 0
        if torn:  # a run ended inside a write: its part-record goes
            self._good -= torn
            os.ftruncate(fd, self._good)
        if self._good == 0 and not self._write(MAGIC):
            raise ConfigError(f"cannot write '{self.path}' — free some space or choose "
                              "another folder")

    def add(self, row: np.ndarray) -> None:
        """Keep one tick's record (one or more :data:`HELD_DTYPE` rows)."""
        self._rows.append(np.ascontiguousarray(row, dtype=HELD_DTYPE).tobytes())
        if len(self._rows) >= FLUSH_RECORDS:
            self.flush()

    def _write(self, data: bytes) -> bool:
        """Append ``data`` whole, or cut the file back and give it up; whether written."""
        fd = self._fd
        if fd is None:
            return False
        view = memoryview(data)
        try:
            while view:
                view = view[os.write(fd, view):]
        except OSError as exc:  # the reader's disk: the run goes on without it
            log.info("held-object truth file %s: %s; no more is written", self.path, exc)
            self.error = exc
            self._fd = None
            with contextlib.suppress(OSError):
                os.ftruncate(fd, self._good)
            os.close(fd)
            return False
        self._good += len(data)
        return True

    def flush(self) -> None:
        """Write what is kept."""
        if self._fd is None or not self._rows:
            self._rows = []
            return
        data = b"".join(self._rows)
        self._rows = []
        if self._write(data):
            self.records += len(data) // HELD_DTYPE.itemsize

    def close(self) -> None:
        """Write the rest and close the file."""
        self.flush()
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


class HeldTruthReader:
    """Reads the records appended to ``path`` since the last :meth:`read` (the file may not
    exist yet, or hold no :data:`MAGIC` yet: nothing then)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._offset = 0

    def read(self) -> np.ndarray:
        """The whole records added since the last call (:data:`HELD_DTYPE`, time order)."""
        try:
            with self.path.open("rb") as f:
                if self._offset == 0:
                    if f.read(len(MAGIC)) != MAGIC:
                        return np.zeros(0, dtype=HELD_DTYPE)
                    self._offset = len(MAGIC)
                f.seek(self._offset)
                data = f.read()
        except FileNotFoundError:
            return np.zeros(0, dtype=HELD_DTYPE)
        whole = len(data) - len(data) % HELD_DTYPE.itemsize
        self._offset += whole
        return np.frombuffer(data[:whole], dtype=HELD_DTYPE).copy()
