"""The held object's truth as a file that grows during the run: the board appends its
records (:data:`skinhil.plant.HELD_DTYPE`, little-endian, no header) as it runs, another
process tails it (the grasp demo's live view). Never on the decoder's link."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import BinaryIO

import numpy as np

from skinhil.plant.truth import HELD_DTYPE

log = logging.getLogger(__name__)

FLUSH_RECORDS = 50
"""Records buffered before a write (50 ticks: 50 ms of 1 ms ticks)."""


class HeldTruthWriter:
    """Appends held-object records to ``path`` (created or truncated), written and flushed
    every :data:`FLUSH_RECORDS` records and at :meth:`close`."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._file: BinaryIO | None = self.path.open("wb")
        self._rows: list[bytes] = []
        self.records = 0
        """Records written so far."""

    def add(self, row: np.ndarray) -> None:
        """Keep one tick's record (one or more :data:`HELD_DTYPE` rows)."""
        self._rows.append(np.ascontiguousarray(row, dtype=HELD_DTYPE).tobytes())
        if len(self._rows) >= FLUSH_RECORDS:
            self.flush()

    def flush(self) -> None:
        """Write what is kept."""
        if self._file is None or not self._rows:
            return
        data = b"".join(self._rows)
        self._rows = []
        try:
            self._file.write(data)
            self._file.flush()
        except OSError as exc:  # the reader's disk: the run goes on without it
            log.warning("held-object truth file %s: %s; no more is written", self.path, exc)
            self._file.close()
            self._file = None
            return
        self.records += len(data) // HELD_DTYPE.itemsize

    def close(self) -> None:
        """Write the rest and close the file."""
        self.flush()
        if self._file is not None:
            self._file.close()
            self._file = None


class HeldTruthReader:
    """Reads the records appended to ``path`` since the last :meth:`read` (the file may not
    exist yet: nothing then)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._offset = 0

    def read(self) -> np.ndarray:
        """The whole records added since the last call (:data:`HELD_DTYPE`, time order)."""
        try:
            with self.path.open("rb") as f:
                f.seek(self._offset)
                data = f.read()
        except FileNotFoundError:
            return np.zeros(0, dtype=HELD_DTYPE)
        whole = len(data) - len(data) % HELD_DTYPE.itemsize
        self._offset += whole
        return np.frombuffer(data[:whole], dtype=HELD_DTYPE).copy()
