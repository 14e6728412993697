"""An offline simulation (``skinhil simulate --out run.nwb``) as an NWB file."""

from __future__ import annotations

import datetime
import math
import uuid
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import Mesh, sensor_positions
from skinhil.model.skin import MODEL_SUMMARY
from skinhil.model.stimuli import Schedule
from skinhil.nwb.metadata import NwbMetadata
from skinhil.output_files import atomic_path

LAYER_NAMES = {1: "layer 1", 2: "layer 2", 3: "layer 3", 12: "layers 1-2", 23: "layers 2-3"}
"""The ``layer`` column of a unit: an in-layer spring, or one between two layers."""


def require_pynwb() -> None:
    """Raise :class:`ConfigError` (one line, the pip command) when pynwb is not installed."""
    try:
        import pynwb  # noqa: F401
    except ImportError:
        raise ConfigError('NWB files need pynwb, which is not installed: '
                          'pip install "skinhil[nwb]"') from None


def new_file(meta: NwbMetadata | None, *, command: str, mesh: Mesh,
             start: datetime.datetime, description: str, experiment: str) -> Any:
    """An :class:`pynwb.NWBFile` with the session's metadata, its subject (the simulated
    skin) and the board as its device."""
    from pynwb import NWBFile

    meta = meta or NwbMetadata()
    nwb = NWBFile(identifier=str(uuid.uuid4()), **meta.nwbfile_kwargs(
        command=command, size=mesh.size, start=start, description=description,
        experiment=experiment))
    nwb.subject = meta.subject(mesh.size, MODEL_SUMMARY, start)
    from skinhil import __version__

    nwb.create_device(name="skinhil_board", description=(
        f"emulated sensor board, skinhil {__version__}: {MODEL_SUMMARY}; "
        f"{mesh.springs.shape[0]} sensors (springs), their rest positions in the units "
        "table's x_m, y_m, z_m"))
    return nwb


def add_units(nwb: Any, mesh: Mesh, events: np.ndarray, resolution_s: float) -> None:
    """One unit per sensor of ``mesh``: its spike times (s, from ``events``' ``t`` in µs)
    and its spring's metadata and rest position; ``resolution_s``: the smallest possible
    difference of two spike times (the board's step, s)."""
    from pynwb.misc import Units

    nwb.units = Units(name="units", resolution=float(resolution_s),
                      description="one unit per sensor (spring) of the skin, by wire address")
    nwb.add_unit_column("spring", "sensor (spring) address, 0-based, as on the wire")
    nwb.add_unit_column("mass_i", "first mass the spring joins, 1-based number M1..")
    nwb.add_unit_column("mass_j", "second mass the spring joins, 1-based number M1..")
    nwb.add_unit_column("layer", "the layer the spring lies in, or the two layers it joins")
    nwb.add_unit_column("rest_length_m", "the spring's rest length (m)")
    for axis, text in (("x", "x (m, to the right on the skin, 0 at its centre)"),
                       ("y", "y (m, up on the skin, 0 at its centre)"),
                       ("z", "z (m, 0 at the top layer, negative below)")):
        nwb.add_unit_column(f"{axis}_m", f"the sensor's position at rest, its spring's "
                                         f"midpoint: {text}")
    order = np.argsort(events["addr"], kind="stable")
    addr = events["addr"][order]
    times = events["t"][order] * 1e-6
    bounds = np.searchsorted(addr, np.arange(mesh.springs.shape[0] + 1))
    where = sensor_positions(mesh)
    for s, (i, j) in enumerate(mesh.springs):
        rest = float(np.linalg.norm(mesh.positions[j] - mesh.positions[i]))
        nwb.add_unit(spike_times=times[bounds[s]:bounds[s + 1]], spring=s,
                     mass_i=int(i) + 1, mass_j=int(j) + 1,
                     layer=LAYER_NAMES.get(int(mesh.layer_of_spring[s]), "?"),
                     rest_length_m=rest, x_m=float(where[s, 0]), y_m=float(where[s, 1]),
                     z_m=float(where[s, 2]))


def _add_trials(nwb: Any, schedule: Schedule) -> None:
    """The stimuli as trials: onset to end of the indentation, with their forces."""
    nwb.add_trial_column("stimulus_id", "ground-truth stimulus id (the wire's marker id)")
    nwb.add_trial_column("stimulus", "stimulus name")
    nwb.add_trial_column("forces", "peak force vector (N) on each pushed mass, 1-based")
    nwb.add_trial_column("force_n", "magnitude of the summed peak force vector (N)")
    nwb.add_trial_column("angle_deg", "in-plane angle of the summed peak force (degrees)")
    for entry in schedule.entries:
        vectors = np.array(list(entry.stimulus.forces.values()), dtype=float).reshape(-1, 3)
        total = vectors.sum(axis=0)
        text = "; ".join(f"M{m}: ({fx:g}, {fy:g}, {fz:g})"
                         for m, (fx, fy, fz) in entry.stimulus.forces.items())
        nwb.add_trial(start_time=float(entry.onset_s), stop_time=float(entry.end_s),
                      stimulus_id=int(entry.stimulus_id), stimulus=entry.stimulus.name,
                      forces=text, force_n=float(np.linalg.norm(total)),
                      angle_deg=float(math.degrees(math.atan2(total[1], total[0]))))


TRUTH_SERIES = (
    ("normal_force", "normal_n", "N", 1.0, "normal force the indenter exerts on the skin"),
    ("tangential_force_x", "tangential_x_n", "N", 1.0, "tangential force along x"),
    ("tangential_force_y", "tangential_y_n", "N", 1.0, "tangential force along y"),
    ("centroid_x", "x_mm", "m", 1e-3, "contact centroid x (NaN: nothing touching)"),
    ("centroid_y", "y_mm", "m", 1e-3, "contact centroid y (NaN: nothing touching)"),
    ("area", "area_mm2", "m^2", 1e-6, "contact area (touching masses x spacing^2)"),
    ("slip_state", "slip", "n.a.", 1.0, "0 none, 1 stick, 2 partial slip, 3 gross slip"),
    ("slip_speed", "slip_speed_mm_per_s", "m/s", 1e-3, "mean slip speed of slipping masses"),
    ("indenter_x", "indenter_x_mm", "m", 1e-3, "indenter axis x"),
    ("indenter_y", "indenter_y_mm", "m", 1e-3, "indenter axis y"),
    ("indenter_depth", "indenter_depth_mm", "m", 1e-3, "indenter tip below the rest surface"),
)
"""The contact truth's fields as NWB time series: name, truth field, unit, conversion to the
unit, description."""


def _add_truth(nwb: Any, truth: np.ndarray, n_contacts: int) -> None:
    """The contacts' ground truth (TRUTH_DTYPE, one record per contact per tick) as time
    series of a processing module ``contact``, one column per contact."""
    from pynwb import TimeSeries

    module = nwb.create_processing_module("contact", "ground truth of every contact per tick "
                                          "(skinhil.world.truth; docs/contact.md)")
    rows = truth.reshape(-1, n_contacts)
    times = rows["t_us"][:, 0] * 1e-6
    period = float(times[1] - times[0]) if len(times) > 1 else 1e-3  # one record per tick
    for name, field, unit, conversion, text in TRUTH_SERIES:
        module.add(TimeSeries(name=name, data=rows[field], unit=unit, conversion=conversion,
                              starting_time=float(times[0]), rate=1.0 / period,
                              description=f"{text}; one column per contact"))


def write_simulation(path: Path, *, mesh: Mesh, schedule: Schedule, events: np.ndarray,
                     forces_n: np.ndarray | None, dt_s: float, description: str,
                     start: datetime.datetime | None = None,
                     meta: NwbMetadata | None = None,
                     truth: np.ndarray | None = None, n_contacts: int = 0) -> Path:
    """Write a simulation to ``path`` (.nwb, atomically) and return the path written.

    ``events``: EVENT_DTYPE (``t`` µs, ``addr``); ``forces_n``: (n_steps, n_springs) N at
    ``dt_s`` (s) from time 0, or None to leave them out; ``start``: the wall-clock time of
    simulation time 0, the file's session start (default: now); ``meta``: the session's
    metadata (default :class:`NwbMetadata`'s); ``truth``: the contacts' ground truth
    (``skinhil.world.TRUTH_DTYPE``, ``n_contacts`` records per tick), or None.
    """
    require_pynwb()
    from pynwb import NWBHDF5IO, TimeSeries

    nwb = new_file(meta, command="simulate", mesh=mesh,
                   start=start or datetime.datetime.now(datetime.UTC), description=description,
                   experiment="an offline simulation of the skin under scheduled touch "
                              "stimuli (skinhil simulate)")
    add_units(nwb, mesh, events, dt_s)
    if schedule.entries:  # a scenario of contacts alone has no stimulus trials
        _add_trials(nwb, schedule)
    if forces_n is not None and forces_n.size:
        nwb.add_acquisition(TimeSeries(
            name="spring_forces", data=forces_n, unit="N", rate=1.0 / dt_s,
            starting_time=0.0,
            description="force across each spring (N, tension positive), one column per "
                        "sensor in wire address order"))
    if truth is not None and truth.size and n_contacts:
        _add_truth(nwb, truth, n_contacts)
    with atomic_path(path) as tmp, NWBHDF5IO(str(tmp), "w") as io:
        io.write(nwb)
    return Path(path).absolute()
