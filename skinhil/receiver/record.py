"""Recording a receiver session: the events (tonic-compatible) and the decisions, to .npz."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.events import EVENT_DTYPE
from skinhil.output_files import atomic_path
from skinhil.receiver.receiver import ReceiverListener
from skinhil.receiver.scoring import ScoredDecision

DECISION_DTYPE = np.dtype([("detect_t_us", "<i8"), ("window_t_us", "<i8"),
                           ("decided_t_us", "<i8"), ("label", "<i4"), ("true_label", "<i4"),
                           ("latency_board_s", "<f8"), ("latency_host_s", "<f8")])
"""One decision: board times (µs), predicted and true class (−1: no marker), latencies (s)."""

MARKER_DTYPE = np.dtype([("t_us", "<i8"), ("stimulus_id", "<i4"), ("phase", "U16")])


class SessionRecorder(ReceiverListener):
    """Keeps every event, marker and decision of a session; :meth:`save` writes an .npz.

    The file holds ``events`` (EVENT_DTYPE: ``t`` µs, ``addr``/``x``, ``p``; what tonic
    reads), ``decisions`` (:data:`DECISION_DTYPE`), ``markers`` and ``meta`` (JSON text).
    """

    def __init__(self) -> None:
        self._events: list[np.ndarray] = []
        self._decisions: list[tuple[Any, ...]] = []
        self._markers: list[tuple[int, int, str]] = []

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        self._events.append(events.copy())

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
    def events(self) -> np.ndarray:
        """All events so far, in arrival order (EVENT_DTYPE)."""
        if not self._events:
            return np.zeros(0, dtype=EVENT_DTYPE)
        return np.concatenate(self._events)

    @property
    def markers(self) -> np.ndarray:
        """Markers received so far (:data:`MARKER_DTYPE`: t_us, stimulus_id, phase)."""
        return np.array(self._markers, dtype=MARKER_DTYPE)

    @property
    def decisions(self) -> np.ndarray:
        return np.array(self._decisions, dtype=DECISION_DTYPE)

    def save(self, path: str | Path, meta: dict[str, Any] | None = None) -> None:
        """Write the session to ``path`` (.npz, plain arrays, no pickle), whole or not at all
        (:func:`skinhil.output_files.atomic_path`)."""
        with atomic_path(Path(path)) as tmp, tmp.open("wb") as fh:
            np.savez_compressed(fh, events=self.events, decisions=self.decisions,
                                markers=self.markers, meta=np.array(json.dumps(meta or {})))
