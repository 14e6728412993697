"""Scenario files: a schedule file (docs/schedule.md) that also holds contact tables.

    [[indenter]]                  # a rigid indenter (docs/contact.md)
    name = "probe"
    shape = "sphere"              # sphere | flat | edge | pins
    radius_mm = 3.0

    [[contact]]                   # the indenter on a trajectory, in the file's time
    indenter = "probe"
    start_s = 0.1
    motion = "slide"              # press | slide | tap | path
    x_mm = -3.0                   # where it starts
    y_mm = 0.0
    to_x_mm = 3.0                 # slide: where it ends, at speed_mm_per_s
    speed_mm_per_s = 20.0
    depth_mm = 0.4                # or load_n: a force-controlled normal load
    vibration_mm = 0.02           # optional: a vibration of this amplitude ...
    vibration_hz = 100.0          # ... and frequency, along vibration_axis (z: depth)

Every key has a type and a range (:data:`CONTACT_LIMITS`, :data:`INDENTER_LIMITS`), unknown
keys are refused, and each refusal is one line naming the table and the key, as the
schedule's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from numbers import Integral, Real
from pathlib import Path

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.schedule_file import (
    checked_table,
    parse_toml,
    read_schedule_text,
    schedule_from_doc,
    table_list,
)
from skinhil.model.skin import SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.validation import Interval, check_param
from skinhil.world.indenters import SHAPES, Indenter
from skinhil.world.scene import MAX_CONTACTS, Contact, Scene
from skinhil.world.trajectory import AXES, MAX_KEYFRAMES, Trajectory

DEFAULT_SPACING_M = SkinParams().spacing_m
"""The skin's mass spacing (m) a scenario is checked against."""
MAX_INDENTERS = 64
"""Most ``[[indenter]]`` tables."""
MAX_DEPTH_MM = 2.0
"""Deepest position-controlled indentation (mm): two spacings of the default skin, strain of
tens of percent; deeper presses stretch springs by hundreds of percent."""
MAX_LOAD_N = 2.0
"""Largest normal load (N): four times the paper's 0.5 N."""
MAX_TAPS = MAX_KEYFRAMES // 3
"""Most taps of one ``tap`` contact: three keyframes each fill one trajectory."""
MAX_PATH_S = 1e5
"""Latest keyframe time (s) of a ``path`` contact (as ``hold_s``)."""
SHAPE_KEYS: dict[str, tuple[str, ...]] = {
    "sphere": ("radius_mm",), "flat": ("radius_mm",),
    "edge": ("radius_mm", "width_mm", "angle_deg"),
    "pins": ("radius_mm", "pitch_mm", "pin_radius_mm"),
}
"""The number keys each indenter shape uses (docs/contact.md); another is refused."""

INDENTER_LIMITS: dict[str, tuple[float, float]] = {
    "radius_mm": (0.05, 100.0), "width_mm": (0.05, 100.0), "angle_deg": (-360.0, 360.0),
    "pitch_mm": (0.1, 100.0), "pin_radius_mm": (0.05, 50.0),
}
"""Range of each number key of ``[[indenter]]`` (inclusive)."""
CONTACT_LIMITS: dict[str, tuple[float, float]] = {
    "start_s": (0.0, 1e6), "x_mm": (-100.0, 100.0), "y_mm": (-100.0, 100.0),
    "to_x_mm": (-100.0, 100.0), "to_y_mm": (-100.0, 100.0),
    "depth_mm": (0.0, MAX_DEPTH_MM), "load_n": (0.0, MAX_LOAD_N),
    "ramp_s": (0.0, 10.0), "hold_s": (0.0, 1e5), "dwell_s": (0.0, 1e5),
    "speed_mm_per_s": (0.01, 1000.0), "taps": (1, MAX_TAPS), "period_s": (1e-3, 1e4),
    "contact_s": (1e-3, 1e4), "vibration_mm": (0.0, 0.5), "vibration_hz": (0.0, 1000.0),
    "mu_static": (0.0, 5.0), "mu_kinetic": (0.0, 5.0),
}
"""Range of each number key of ``[[contact]]`` (inclusive)."""
MOTIONS = ("press", "slide", "tap", "path")
MOTION_KEYS = {
    "press": ("x_mm", "y_mm", "ramp_s", "hold_s"),
    "slide": ("x_mm", "y_mm", "to_x_mm", "to_y_mm", "speed_mm_per_s", "ramp_s", "dwell_s"),
    "tap": ("x_mm", "y_mm", "taps", "period_s", "contact_s"),
    "path": ("path",),
}
"""The keys each motion takes besides the common ones."""
COMMON_KEYS = ("indenter", "start_s", "motion", "depth_mm", "load_n", "vibration_mm",
               "vibration_hz", "vibration_axis", "mu_static", "mu_kinetic", "name")
INDENTER_KEYS = ("name", "shape", *INDENTER_LIMITS)


@dataclass(frozen=True)
class Scenario:
    """A scenario file's stimuli (possibly none) and its contacts (None if it has none)."""

    schedule: Schedule
    scene: Scene | None

    @property
    def duration_s(self) -> float:
        """Time (s) at which the last stimulus or contact ends."""
        return max(self.schedule.duration_s, self.scene.duration_s if self.scene else 0.0)


def _number(t: Mapping[str, object], key: str, where: str,
            limits: Mapping[str, tuple[float, float]], default: float | None = None) -> float:
    if key not in t:
        if default is None:
            raise ConfigError(f"{where}: needs {key} = <number>")
        return default
    value = t[key]
    lo, hi = limits[key]
    check_param(key, value, Interval(Real, lo, hi, closed="both", hint="no quotes"),
                where=f"{where}: ")
    return float(value)  # type: ignore[arg-type]


def _name(t: Mapping[str, object], where: str, default: str | None = None) -> str:
    name = t.get("name", default)
    if not (isinstance(name, str) and 0 < len(name) <= 64):
        raise ConfigError(f"{where}: name = {name!r} — give 1..64 characters in quotes")
    return name


def _indenter(table: object, where: str) -> tuple[str, Indenter]:
    t = checked_table(table, INDENTER_KEYS, where)
    name = _name(t, where)
    shape = t.get("shape")
    if shape not in SHAPES:
        raise ConfigError(f"{where}: shape = {shape!r} — give one of {', '.join(SHAPES)}")
    unused = [k for k in INDENTER_LIMITS if k in t and k not in SHAPE_KEYS[str(shape)]]
    if unused:
        raise ConfigError(f"{where}: a {shape} has no {', '.join(unused)} — give "
                          f"{' and '.join(SHAPE_KEYS[str(shape)])} only")
    mm = {k: _number(t, k, where, INDENTER_LIMITS) * 1e-3
          for k in ("radius_mm", "width_mm", "pitch_mm", "pin_radius_mm") if k in t}
    kwargs = {k.replace("_mm", "_m"): v for k, v in mm.items()}
    if "angle_deg" in t:
        kwargs["angle_deg"] = _number(t, "angle_deg", where, INDENTER_LIMITS)
    try:
        return name, Indenter(shape, **kwargs)  # type: ignore[arg-type]
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _path(value: object, where: str) -> np.ndarray:
    if not (isinstance(value, list) and 1 <= len(value) <= MAX_KEYFRAMES and all(
            isinstance(row, list) and len(row) == 4 and all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in row) for row in value)):
        raise ConfigError(f"{where}: path — give 1..{MAX_KEYFRAMES} keyframes "
                          "[t_s, x_mm, y_mm, depth_mm (or load_n)]")
    k = np.array(value, dtype=float)
    if np.any(np.diff(k[:, 0]) < 0) or k[0, 0] < 0 or k[-1, 0] > MAX_PATH_S:
        raise ConfigError(f"{where}: path times must start >= 0, not decrease and end by "
                          f"{MAX_PATH_S:g} s")
    if np.any(np.abs(k[:, 1:3]) > 100) or np.any(k[:, 3] < 0) or np.any(k[:, 3] > MAX_DEPTH_MM):
        raise ConfigError(f"{where}: path x_mm, y_mm within ±100, depth within "
                          f"0..{MAX_DEPTH_MM:g} mm")
    k[:, 1:] *= 1e-3
    return k


def _contact(table: object, where: str, indenters: Mapping[str, Indenter],
             index: int) -> Contact:
    motion = table.get("motion") if isinstance(table, Mapping) else None
    if motion not in MOTIONS:
        raise ConfigError(f"{where}: motion = {motion!r} — give one of {', '.join(MOTIONS)}")
    t = checked_table(table, COMMON_KEYS + MOTION_KEYS[motion], where)
    which = t.get("indenter")
    if not isinstance(which, str) or which not in indenters:
        raise ConfigError(f"{where}: indenter = {which!r} — give the name of an "
                          f"[[indenter]]: {', '.join(indenters) or 'none defined'}")
    force = "load_n" in t
    if force == ("depth_mm" in t) and motion != "path":
        raise ConfigError(f"{where}: give depth_mm (position control) or load_n (a normal "
                          "load), one of them")
    if force and motion in ("tap", "path"):
        raise ConfigError(f"{where}: a {motion} is position-controlled: give depth_mm")
    if motion == "path" and "depth_mm" in t:
        raise ConfigError(f"{where}: a path's depths are its keyframes' — drop depth_mm")
    idle = [k for k in ("vibration_hz", "vibration_axis") if k in t]
    if idle and not t.get("vibration_mm"):
        raise ConfigError(f"{where}: {' and '.join(idle)} without vibration_mm above 0 "
                          "move nothing — give vibration_mm, or drop them")
    value = (_number(t, "load_n", where, CONTACT_LIMITS) if force
             else _number(t, "depth_mm", where, CONTACT_LIMITS, 0.0) * 1e-3)
    def mm(key: str, default: float | None = None) -> float:
        return _number(t, key, where, CONTACT_LIMITS,
                       None if default is None else default * 1e3) * 1e-3
    def num(key: str, default: float | None = None) -> float:
        return _number(t, key, where, CONTACT_LIMITS, default)
    try:
        if motion == "press":
            traj = Trajectory.press(mm("x_mm", 0.0), mm("y_mm", 0.0), value, num("ramp_s", 0.02),
                                    num("hold_s", 0.2), load=force)
        elif motion == "slide":
            traj = Trajectory.slide((mm("x_mm"), mm("y_mm", 0.0)),
                                    (mm("to_x_mm"), mm("to_y_mm", 0.0)),
                                    num("speed_mm_per_s") * 1e-3, value, num("ramp_s", 0.02),
                                    num("dwell_s", 0.05), load=force)
        elif motion == "tap":
            if "taps" in t:
                check_param("taps", t["taps"], Interval(Integral, *CONTACT_LIMITS["taps"],
                                                        closed="both", hint="a whole number"))
            traj = Trajectory.taps(mm("x_mm", 0.0), mm("y_mm", 0.0), value, int(num("taps")),
                                   num("period_s"), num("contact_s"))
        else:
            if "path" not in t:
                raise ConfigError("needs path = [[t_s, x_mm, y_mm, depth_mm], ...]")
            traj = Trajectory(_path(t["path"], where))
        amp = num("vibration_mm", 0.0) * 1e-3
        if amp > 0:
            axis = t.get("vibration_axis", "z")
            if axis not in AXES:
                raise ConfigError(f"vibration_axis = {axis!r} — give x, y or z")
            traj = traj.with_vibration(amp, num("vibration_hz"), str(axis))
        return Contact(indenters[which], traj, num("start_s", 0.0), num("mu_static", 0.8),
                       num("mu_kinetic", 0.6), _name(t, where, f"contact{index}"))
    except ConfigError as exc:
        text = str(exc)
        raise ConfigError(text if text.startswith(where) else f"{where}: {text}") from None


def _check_touches(contact: Contact, where: str, size: MeshSize, spacing_m: float) -> None:
    """Refuse a contact whose indenter never comes over the skin's top layer (``size``
    masses ``spacing_m`` apart, centred on the origin): it would touch nothing."""
    traj = contact.trajectory
    if traj.tangential == "force":  # moved by a load: where it goes is not known here
        return
    rows, cols = size
    half_x, half_y = (cols - 1) / 2 * spacing_m, (rows - 1) / 2 * spacing_m
    reach = contact.indenter.reach_m + traj.vibration_amplitude_m
    xy = traj.keyframes[:, 1:3]
    if (xy[:, 0].max() < -half_x - reach or xy[:, 0].min() > half_x + reach
            or xy[:, 1].max() < -half_y - reach or xy[:, 1].min() > half_y + reach):
        raise ConfigError(
            f"{where}: the indenter never comes over the skin (x and y within "
            f"±{half_x * 1e3:g} mm and ±{half_y * 1e3:g} mm on a {size[0]}x{size[1]} skin, "
            f"plus its reach {reach * 1e3:g} mm): it would touch nothing — move it onto "
            "the skin")


def parse_scenario(text: str, where: str, size: MeshSize = PAPER_SIZE,
                   spacing_m: float = DEFAULT_SPACING_M) -> Scenario:
    """The scenario of TOML ``text`` (named ``where`` in errors) for a skin of ``size``
    (top-layer masses ``spacing_m`` apart)."""
    doc = parse_toml(text, where)
    contacts_in = table_list(doc, "contact", MAX_CONTACTS, where)
    indenters: dict[str, Indenter] = {}
    for i, table in enumerate(table_list(doc, "indenter", MAX_INDENTERS, where)):
        name, ind = _indenter(table, f"{where}: [[indenter]] #{i + 1}")
        if name in indenters:
            raise ConfigError(f"{where}: [[indenter]] #{i + 1}: name = {name!r} is taken by "
                              "an earlier [[indenter]] — give each a distinct name")
        indenters[name] = ind
    schedule = schedule_from_doc(doc, where, size, ("indenter", "contact"),
                                 events_required=not contacts_in)
    contacts = tuple(_contact(t, f"{where}: [[contact]] #{i + 1}", indenters, i)
                     for i, t in enumerate(contacts_in))
    names = [c.name for c in contacts]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ConfigError(f"{where}: [[contact]] #{i + 1}: name = {name!r} is taken by an "
                              "earlier [[contact]] (the truth names each) — give each a "
                              "distinct name")
    for i, contact in enumerate(contacts):
        _check_touches(contact, f"{where}: [[contact]] #{i + 1}", size, spacing_m)
    return Scenario(schedule, Scene(contacts) if contacts else None)


def load_scenario(path: str | Path, size: MeshSize = PAPER_SIZE) -> Scenario:
    """Read the scenario (or plain schedule) file ``path`` for a skin of ``size``; the same
    caps as a schedule file (:func:`skinhil.model.schedule_file.load_schedule`)."""
    text, where = read_schedule_text(path)
    return parse_scenario(text, where, size)
