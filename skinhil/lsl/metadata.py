"""The ``desc`` of skinhil's LSL streams, per the XDF meta-data conventions: who made the
data (``acquisition``), from what (``provenance``), and each channel's label, unit, type
and place on the skin (``channels/channel/location`` X, Y, Z in millimetres, as the
conventions place EEG electrodes).

``acquisition``: ``manufacturer`` skinhil, ``model`` (the emulated skin and neurons),
``software_version``. ``provenance``: what the receiver knows of the run, every value a
string: ``skinhil_version``, ``model``, ``size`` (top layer ROWSxCOLS), ``sensors``,
``board`` (its id or UDP source), ``link``, ``decoder`` (the model file), ``decoder_sha256``,
and ``snr_db`` and ``seed`` as the caller gives them (the wire does not carry the board's;
``unknown`` until the board says).

Sensor coordinates: a sensor's place is its spring's midpoint at rest
(:func:`skinhil.model.geometry.sensor_positions`), X to the right and Y up on the skin,
0 at its centre, Z 0 at the top layer and negative below it, in mm.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from skinhil.model.geometry import Mesh, sensor_label, sensor_positions
from skinhil.model.skin import MODEL_SUMMARY


def add_location(node: Any, xyz_m: np.ndarray) -> None:
    """``location`` X, Y, Z (mm, 4 decimals) under ``node``."""
    loc = node.append_child("location")
    for axis, v in zip("XYZ", xyz_m, strict=True):
        loc.append_child_value(axis, f"{1e3 * float(v):.4f}")


def describe(info: Any, provenance: Mapping[str, str]) -> None:
    """``acquisition`` and ``provenance`` in ``info``'s desc."""
    from skinhil import __version__

    acq = info.desc().append_child("acquisition")
    acq.append_child_value("manufacturer", "skinhil")
    acq.append_child_value("model", MODEL_SUMMARY)
    acq.append_child_value("software_version", __version__)
    prov = info.desc().append_child("provenance")
    for key, value in {"skinhil_version": __version__, "model": MODEL_SUMMARY,
                       **provenance}.items():
        prov.append_child_value(key, str(value))


def add_sensor_channels(info: Any, mesh: Mesh, addresses: list[int], unit: str,
                        kind: str) -> None:
    """One ``channels/channel`` per sensor of ``addresses``: label, unit, type, its
    address and masses, its location."""
    where = sensor_positions(mesh)
    chans = info.desc().append_child("channels")
    for a in addresses:
        i, j = mesh.springs[a]
        c = chans.append_child("channel")
        c.append_child_value("label", sensor_label(mesh, a))
        c.append_child_value("unit", unit)
        c.append_child_value("type", kind)
        c.append_child_value("sensor", str(a))
        c.append_child_value("mass_i", f"M{int(i) + 1}")
        c.append_child_value("mass_j", f"M{int(j) + 1}")
        add_location(c, where[a])


def add_sensor_table(info: Any, mesh: Mesh) -> None:
    """``sensors/sensor`` for every sensor (a spike's value is its address): address, the
    spring's two masses, the location."""
    where = sensor_positions(mesh)
    table = info.desc().append_child("sensors")
    for a in range(int(mesh.springs.shape[0])):
        i, j = mesh.springs[a]
        s = table.append_child("sensor")
        s.append_child_value("address", str(a))
        s.append_child_value("mass_i", f"M{int(i) + 1}")
        s.append_child_value("mass_j", f"M{int(j) + 1}")
        add_location(s, where[a])


def add_plain_channels(info: Any, channels: list[tuple[str, str, str]]) -> None:
    """``channels/channel`` of (label, unit, type) each."""
    chans = info.desc().append_child("channels")
    for label, unit, kind in channels:
        c = chans.append_child("channel")
        c.append_child_value("label", label)
        if unit:
            c.append_child_value("unit", unit)
        c.append_child_value("type", kind)
