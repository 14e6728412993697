"""Recording a receiver session (``listen --record``): the events (tonic-compatible), the
ground-truth markers and the decisions, streamed to disk as they arrive.

Events go to a spool file (raw :data:`skinhil.events.EVENT_DTYPE` records) beside the output
as they are decoded, so a session of any length holds no events in memory; :meth:`save`
assembles the .npz from the spool chunk by chunk. The spool is named after its process, so
the spool of a recorder killed by SIGKILL is removed by the next recorder in its folder.
Markers and decisions (a few per stimulus) are kept in memory.
"""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.events import EVENT_DTYPE
from skinhil.output_files import atomic_path
from skinhil.receiver.receiver import ReceiverListener
from skinhil.receiver.scoring import ScoredDecision
from skinhil.temp_folders import process_tag, remove_stale

DECISION_DTYPE = np.dtype([("detect_t_us", "<i8"), ("window_t_us", "<i8"),
                           ("decided_t_us", "<i8"), ("label", "<i4"), ("true_label", "<i4"),
                           ("latency_board_s", "<f8"), ("latency_host_s", "<f8")])
"""One decision: board times (µs), predicted and true class (−1: no marker), latencies (s)."""

MARKER_DTYPE = np.dtype([("t_us", "<i8"), ("stimulus_id", "<i4"), ("phase", "U16")])

SPOOL_PREFIX = ".skinhil-events."
"""The spool file's name before its process tag (:func:`skinhil.temp_folders.process_tag`):
a recorder removes the spools of ended processes in its folder as it starts."""
COPY_CHUNK_EVENTS = 1 << 16
"""Events copied from the spool into the .npz at a time (0.7 MB)."""


class SessionRecorder(ReceiverListener):
    """Streams every event of a session to a spool file and keeps its markers and decisions;
    :meth:`save` writes an .npz.

    The file holds ``events`` (EVENT_DTYPE: ``t`` µs, ``addr``/``x``, ``p``; what tonic
    reads), ``decisions`` (:data:`DECISION_DTYPE`), ``markers`` and ``meta`` (JSON text).
    ``spool_dir``: the folder of the spool file (default: the system's temporary folder);
    :meth:`close` removes it.
    """

    def __init__(self, spool_dir: str | Path | None = None) -> None:
        folder = Path(tempfile.gettempdir() if spool_dir is None else spool_dir)
        remove_stale(folder, SPOOL_PREFIX)  # the spools of killed recorders
        fd, name = tempfile.mkstemp(prefix=f"{SPOOL_PREFIX}{process_tag()}.", suffix=".spool",
                                    dir=str(folder))
        self._spool_path = Path(name)
        self._spool = os.fdopen(fd, "w+b")
        self._n_events = 0
        self._decisions: list[tuple[Any, ...]] = []
        self._markers: list[tuple[int, int, str]] = []

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        self._spool.write(np.ascontiguousarray(events, dtype=EVENT_DTYPE).tobytes())
        self._n_events += len(events)

    def on_marker(self, marker: Any) -> None:
        phase = getattr(marker.phase, "name", str(marker.phase)).lower()
        self._markers.append((int(marker.t_us), int(marker.stimulus_id), phase))

    def on_decision(self, decision: ScoredDecision) -> None:
        p = decision.prediction
        nan = float("nan")
        self._decisions.append((p.detect_t_us, p.window_t_us, p.decided_t_us, p.label,
                                -1 if decision.true_label is None else decision.true_label,
                                nan if decision.latency_board_s is None
                                else decision.latency_board_s,
                                nan if decision.latency_host_s is None
                                else decision.latency_host_s))

    @property
    def n_events(self) -> int:
        """Events recorded so far."""
        return self._n_events

    @property
    def events(self) -> np.ndarray:
        """All events so far, in arrival order (EVENT_DTYPE), mapped from the spool file
        (read-only; pages are read from disk as they are used)."""
        if not self._n_events:
            return np.zeros(0, dtype=EVENT_DTYPE)
        self._spool.flush()
        return np.memmap(self._spool_path, dtype=EVENT_DTYPE, mode="r",
                         shape=(self._n_events,))

    @property
    def markers(self) -> np.ndarray:
        """Markers received so far (:data:`MARKER_DTYPE`: t_us, stimulus_id, phase)."""
        return np.array(self._markers, dtype=MARKER_DTYPE)

    @property
    def decisions(self) -> np.ndarray:
        """Decisions so far (:data:`DECISION_DTYPE`)."""
        return np.array(self._decisions, dtype=DECISION_DTYPE)

    def save(self, path: str | Path, meta: dict[str, Any] | None = None) -> Path:
        """Write the session to ``path`` (.npz, plain arrays, no pickle, compressed),
        atomically, copying the events from the spool in chunks; return the path."""
        self._spool.flush()
        with atomic_path(Path(path)) as tmp, \
                zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
            with zf.open("events.npy", "w", force_zip64=True) as f:
                np.lib.format.write_array_header_1_0(f, {
                    "descr": np.lib.format.dtype_to_descr(EVENT_DTYPE),
                    "fortran_order": False, "shape": (self._n_events,)})
                self._spool.seek(0)
                buf = bytearray(COPY_CHUNK_EVENTS * EVENT_DTYPE.itemsize)  # reused: no churn
                view = memoryview(buf)
                while n := self._spool.readinto(buf):
                    f.write(view[:n])
                self._spool.seek(0, os.SEEK_END)
            for name, arr in (("decisions", self.decisions), ("markers", self.markers),
                              ("meta", np.array(json.dumps(meta or {})))):
                with zf.open(f"{name}.npy", "w") as f:
                    np.lib.format.write_array(f, arr, allow_pickle=False)
        return Path(path).absolute()

    def close(self) -> None:
        """Remove the spool file (the recorder keeps no events after this)."""
        if not self._spool.closed:
            self._spool.close()
        self._spool_path.unlink(missing_ok=True)

    def __enter__(self) -> SessionRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
