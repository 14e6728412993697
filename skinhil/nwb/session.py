"""A receiver session (``skinhil listen --record session.nwb``) as an NWB file."""

from __future__ import annotations

import datetime
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.model.geometry import Mesh
from skinhil.nwb.metadata import NwbMetadata
from skinhil.nwb.simulation import add_units, new_file, require_pynwb
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


def time_resolution_s(events: np.ndarray) -> float:
    """The smallest possible difference of two spike times (s) as the received times show
    it: their greatest common divisor in µs (the board's step, 100 µs by default; a whole
    µs, the wire's unit, when there are too few to tell)."""
    t = np.unique(np.asarray(events["t"], dtype=np.int64))
    step = int(np.gcd.reduce(np.diff(t))) if t.size > 2 else 1
    return max(step, 1) / 1e6


def write_session(path: Path, *, mesh: Mesh, events: np.ndarray, markers: np.ndarray,
                  decisions: np.ndarray, names: dict[int, str], description: str,
                  start: datetime.datetime | None = None,
                  meta: NwbMetadata | None = None) -> Path:
    """Write a recorded session to ``path`` (.nwb, atomically); return the path written.

    ``events``: EVENT_DTYPE (``t`` µs board time); ``markers`` and ``decisions`` as
    :class:`skinhil.recording.SessionRecorder` keeps them; ``names``: stimulus id →
    name; ``start``: the wall-clock time of board time 0 (the receiver's clock model,
    :meth:`skinhil.receiver.BoardClock.wall_time`; default now), so every time in the file
    is board time and the file lines up with other recordings of the same wall clock;
    ``meta``: the session's metadata (default :class:`NwbMetadata`'s).
    """
    require_pynwb()
    from pynwb import NWBHDF5IO

    nwb = new_file(meta, command="listen", mesh=mesh,
                   start=start or datetime.datetime.now(datetime.UTC), description=description,
                   experiment="a board's spike stream received, decoded and classified "
                              "online (skinhil listen)")
    add_units(nwb, mesh, events, time_resolution_s(events))
    _add_stimuli(nwb, markers, names)
    _add_decisions(nwb, decisions, names)
    with atomic_path(path) as tmp, NWBHDF5IO(str(tmp), "w") as io:
        io.write(nwb)
    return Path(path).absolute()
