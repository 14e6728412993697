"""A receiver session (``skinhil listen --record session.nwb``) as an NWB file."""

from __future__ import annotations

import datetime
import uuid
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.model.geometry import Mesh
from skinhil.nwb.simulation import add_units, require_pynwb
from skinhil.output_files import atomic_path


def _add_stimuli(nwb: Any, markers: np.ndarray, names: dict[int, str]) -> None:
    """Each ground-truth ONSET marker as a trial, until that stimulus' END marker (or the
    next onset, or the onset itself when the stream ended first)."""
    onsets = markers[markers["phase"] == "onset"]
    if onsets.size == 0:
        return  # no stimulus seen: no trials table (NWB has no typed empty column)
    nwb.add_trial_column("stimulus_id", "ground-truth stimulus id (the wire's marker id)")
    nwb.add_trial_column("stimulus", "stimulus name")
    ends = markers[markers["phase"] == "end"]
    for k, m in enumerate(onsets):
        later = ends[(ends["t_us"] >= m["t_us"]) & (ends["stimulus_id"] == m["stimulus_id"])]
        stop = int(later["t_us"][0]) if later.size else (
            int(onsets["t_us"][k + 1]) if k + 1 < onsets.size else int(m["t_us"]))
        nwb.add_trial(start_time=m["t_us"] * 1e-6, stop_time=stop * 1e-6,
                      stimulus_id=int(m["stimulus_id"]),
                      stimulus=names.get(int(m["stimulus_id"]), str(int(m["stimulus_id"]))))


def _add_decisions(nwb: Any, decisions: np.ndarray, names: dict[int, str]) -> None:
    """The receiver's decisions: from the detected onset to the decision (board time, s)."""
    from pynwb.epoch import TimeIntervals

    if decisions.size == 0:
        return
    table = TimeIntervals(name="decisions", description="online decisions of the receiver: "
                          "start = detected onset, stop = decision time (board time, s)")
    table.add_column("label", "decided stimulus id")
    table.add_column("decided", "decided stimulus name")
    table.add_column("true_label", "ground-truth stimulus id (-1: no marker matched)")
    table.add_column("latency_board_s", "decision time minus true onset, board time (s)")
    for d in decisions:
        table.add_row(start_time=d["detect_t_us"] * 1e-6,
                      stop_time=max(d["decided_t_us"], d["detect_t_us"]) * 1e-6,
                      label=int(d["label"]), decided=names.get(int(d["label"]), "?"),
                      true_label=int(d["true_label"]),
                      latency_board_s=float(d["latency_board_s"]))
    nwb.add_time_intervals(table)


def write_session(path: Path, *, mesh: Mesh, events: np.ndarray, markers: np.ndarray,
                  decisions: np.ndarray, names: dict[int, str], description: str) -> Path:
    """Write a recorded session to ``path`` (.nwb, atomically); return the path written.

    ``events``: EVENT_DTYPE (``t`` µs board time); ``markers`` and ``decisions`` as
    :class:`skinhil.recording.SessionRecorder` keeps them; ``names``: stimulus id →
    name.
    """
    require_pynwb()
    from pynwb import NWBHDF5IO, NWBFile

    nwb = NWBFile(session_description=description, identifier=str(uuid.uuid4()),
                  session_start_time=datetime.datetime.now(datetime.UTC),
                  source_script="skinhil listen", source_script_file_name="skinhil")
    add_units(nwb, mesh, events)
    _add_stimuli(nwb, markers, names)
    _add_decisions(nwb, decisions, names)
    with atomic_path(path) as tmp, NWBHDF5IO(str(tmp), "w") as io:
        io.write(nwb)
    return Path(path).absolute()
