"""Schedule files: a TOML timeline of stimuli, checked against a schema before any use.

The format and its limits are documented in ``docs/schedule.md``; in short::

    [[stimulus]]                 # optional user stimuli (ids 100, 101, ... in file order)
    name = "poke"
    forces = { 15 = [0.0, 0.0, -0.4], 16 = [0.0, 0.0, -0.1] }   # N, mass numbers
    indentation_s = 0.2          # optional: onset_s, indentation_s, decay_tau_s
    decay_tau_s = 0.05

    [[event]]                    # the timeline
    start_s = 0.5
    stimulus = "poke"            # a user stimulus or a built-in ("A".."E", "0deg_0.1N", ...)

Every value has a type and a range (:data:`LIMITS`), unknown keys are refused, and the file
is capped in size (:data:`MAX_FILE_BYTES`), number of stimuli and events, and nesting, so a
hostile or mistaken file is refused with one line naming the entry and the key, in well
under a second, whatever it holds.
"""

from __future__ import annotations

import math
import os
import select
import stat
import time
import tomllib
from collections.abc import Mapping
from numbers import Real
from pathlib import Path

from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.stimuli import (
    MAX_FORCE_N,
    USER_STIMULUS_ID_BASE,
    Schedule,
    ScheduledStimulus,
    Stimulus,
    builtin_catalog,
    check_total_force,
)
from skinhil.validation import Interval, check_param

MAX_FILE_BYTES = 4 * 1024 * 1024
"""Largest schedule file (4 MiB: about 60,000 events)."""
READ_TIMEOUT_S = 10.0
"""Longest wait (s) for a schedule that is not a regular file (a pipe, a device) to end."""
MAX_STIMULI = 1000
"""Most ``[[stimulus]]`` tables."""
MAX_EVENTS = 100_000
"""Most ``[[event]]`` tables."""
MAX_NAME_CHARS = 64
"""Longest stimulus name."""
MAX_TIME_S = 1e6
"""Largest time (s, 11.6 days) of any ``start_s``, ``onset_s``, ``indentation_s`` or
``decay_tau_s``."""

STIMULUS_KEYS = ("name", "forces", "onset_s", "indentation_s", "decay_tau_s")
EVENT_KEYS = ("start_s", "stimulus")
_TIME = Interval(Real, 0.0, MAX_TIME_S, closed="both", unit="s", hint="no quotes")
LIMITS: dict[str, Interval] = {
    "start_s": _TIME,
    "onset_s": _TIME,
    "indentation_s": _TIME,
    "decay_tau_s": Interval(Real, 0.0, math.inf, closed="right", unit="s",
                            hint="inf: a constant force; no quotes"),
}
"""What each number key takes."""


def _number(value: object, where: str, key: str) -> float:
    check_param(key, value, LIMITS[key], where=f"{where}: ")
    return float(value)  # type: ignore[arg-type]


def _force(value: object, where: str, mass: str) -> tuple[float, float, float]:
    if not (isinstance(value, list) and len(value) == 3
            and all(isinstance(v, int | float) and not isinstance(v, bool)
                    and math.isfinite(v) and abs(v) <= MAX_FORCE_N for v in value)):
        raise ConfigError(f"{where}: forces.{mass} = {value!r} — give [fx, fy, fz], three "
                          f"numbers of newtons within ±{MAX_FORCE_N:g}")
    return float(value[0]), float(value[1]), float(value[2])


def checked_table(table: object, allowed: tuple[str, ...], where: str) -> Mapping[str, object]:
    """``table`` as a TOML table holding only ``allowed`` keys, else a one-line ConfigError."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where} is not a table — write it as [[...]] with keys "
                          f"{', '.join(allowed)}")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {', '.join(unknown)} — allowed: "
                          f"{', '.join(allowed)}")
    return table


def _stimulus(table: object, where: str, size: MeshSize) -> Stimulus:
    t = checked_table(table, STIMULUS_KEYS, where)
    name, forces = t.get("name"), t.get("forces")
    if not (isinstance(name, str) and 0 < len(name) <= MAX_NAME_CHARS):
        raise ConfigError(f"{where}: name = {name!r} — give a name of 1..{MAX_NAME_CHARS} "
                          "characters in quotes")
    if not (isinstance(forces, Mapping) and forces):
        raise ConfigError(f"{where}: forces = {forces!r} — give a table such as "
                          "forces = { 15 = [0.0, 0.0, -0.4] } (mass number = [fx, fy, fz] N)")
    vectors = {mass: _force(vec, where, mass) for mass, vec in forces.items()}
    times = {k: _number(t[k], where, k) for k in ("onset_s", "indentation_s", "decay_tau_s")
             if k in t}
    return Stimulus(name, vectors, size=size, **times)  # type: ignore[arg-type]


def table_list(doc: Mapping[str, object], key: str, cap: int, where: str) -> list[object]:
    """The ``[[key]]`` tables of ``doc`` (at most ``cap``), else a one-line ConfigError."""
    tables = doc.get(key, [])
    if not isinstance(tables, list):
        raise ConfigError(f"{where}: '{key}' is not a list of tables — write [[{key}]]")
    if len(tables) > cap:
        raise ConfigError(f"{where} has {len(tables)} [[{key}]] tables — at most {cap}; "
                          "split the schedule")
    return tables


def parse_toml(text: str, where: str) -> dict[str, object]:
    """The TOML document of ``text`` (named ``where`` in errors), or :class:`ConfigError`."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where} is not valid TOML: {exc} — see docs/schedule.md") from None
    except RecursionError:
        raise ConfigError(f"{where} nests arrays or tables too deeply — a schedule nests at "
                          "most 3 levels (see docs/schedule.md)") from None


def parse_schedule(text: str, where: str, size: MeshSize = PAPER_SIZE) -> Schedule:
    """The schedule of TOML ``text`` (named ``where`` in errors) for a skin of top-layer
    ``size``. Raises :class:`ConfigError` naming the entry and key for anything off-schema."""
    return schedule_from_doc(parse_toml(text, where), where, size)


def schedule_from_doc(doc: Mapping[str, object], where: str, size: MeshSize = PAPER_SIZE,
                      other_sections: tuple[str, ...] = (),
                      events_required: bool = True) -> Schedule:
    """The schedule of a parsed TOML document (:func:`parse_schedule`); ``other_sections``
    are left to the caller (the contact tables of :mod:`skinhil.world.scenario_file`), and
    without ``events_required`` a file without ``[[event]]`` gives an empty schedule."""
    sections = ("stimulus", "event") + other_sections
    unknown = sorted(set(doc) - set(sections))
    if unknown:
        raise ConfigError(f"{where}: unknown section(s) {', '.join(unknown)} — use "
                          f"{', '.join(f'[[{s}]]' for s in sections)}")
    catalog = builtin_catalog(size)
    for i, table in enumerate(table_list(doc, "stimulus", MAX_STIMULI, where)):
        at = f"{where}: [[stimulus]] #{i + 1}"
        stim = _stimulus(table, at, size)
        if stim.name in catalog:  # one name would play two stimuli
            taken = ("an earlier [[stimulus]]" if catalog[stim.name][0] >= USER_STIMULUS_ID_BASE
                     else "a built-in stimulus")
            raise ConfigError(f"{at}: name = {stim.name!r} is taken by {taken} — give it "
                              "another name")
        catalog[stim.name] = (USER_STIMULUS_ID_BASE + i, stim)
    events = table_list(doc, "event", MAX_EVENTS, where)
    if not events and events_required:
        raise ConfigError(f"{where} has no [[event]] entries — add [[event]] tables with "
                          "start_s and stimulus")
    entries = []
    for i, table in enumerate(events):
        at = f"{where}: [[event]] #{i + 1}"
        ev = checked_table(table, EVENT_KEYS, at)
        if "start_s" not in ev or "stimulus" not in ev:
            raise ConfigError(f"{at}: needs start_s = <seconds> and stimulus = \"name\"")
        name = ev["stimulus"]
        if not isinstance(name, str) or name not in catalog:
            raise ConfigError(f"{at}: unknown stimulus {name!r} — give the name of a "
                              f"[[stimulus]] or a built-in: {', '.join(builtin_catalog())}")
        sid, stim = catalog[name]
        entries.append(ScheduledStimulus(_number(ev["start_s"], at, "start_s"), stim, sid))
    check_total_force(entries, where)
    return Schedule(tuple(entries))


def _read_bounded(p: Path, where: str, max_bytes: int = MAX_FILE_BYTES) -> bytes:
    """At most ``max_bytes + 1`` bytes of ``p``; a FIFO or a device (not a regular file)
    is read without blocking for at most :data:`READ_TIMEOUT_S`, so a pipe nobody writes
    to cannot hang the command."""
    fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK)
    try:
        if stat.S_ISREG(os.fstat(fd).st_mode):
            os.set_blocking(fd, True)
            with os.fdopen(os.dup(fd), "rb") as fh:
                return fh.read(max_bytes + 1)
        chunks: list[bytes] = []
        size = 0
        deadline = time.monotonic() + READ_TIMEOUT_S
        while size <= max_bytes:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise ConfigError(f"{where} gave no end of data within {READ_TIMEOUT_S:g} s "
                                  "(a pipe or device nobody writes to?) — give a regular file")
            try:
                chunk = os.read(fd, 65536)
            except BlockingIOError:
                continue
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def load_schedule(path: str | Path, size: MeshSize = PAPER_SIZE) -> Schedule:
    """Read the schedule file ``path`` (format and caps: module docstring, docs/schedule.md)
    for a skin of top-layer ``size`` (mass numbers of that size; built-in stimuli moved to it
    by :func:`skinhil.model.stimuli.at_size`).

    Raises :class:`ConfigError` naming the problem for a missing, unreadable, oversized or
    malformed file.
    """
    text, where = read_schedule_text(path)
    return parse_schedule(text, where, size)


def read_schedule_text(path: str | Path, what: str = "schedule file",
                       max_bytes: int = MAX_FILE_BYTES,
                       too_big: str = "split it into shorter schedules") -> tuple[str, str]:
    """The text of the file ``path`` and its name for errors (``what`` and the path: a
    schedule file, a campaign file, a campaign summary), within ``max_bytes`` (default
    :data:`MAX_FILE_BYTES`; ``too_big`` says what to do past it); :class:`ConfigError` for a
    missing, unreadable, oversized or non-UTF-8 file."""
    p = Path(path)
    where = f"{what} {str(p)!r}"
    try:
        data = _read_bounded(p, where, max_bytes)
    except FileNotFoundError:
        raise ConfigError(f"{where} not found — check the path") from None
    except OSError as exc:
        raise ConfigError(f"{where} cannot be read: {exc.strerror or exc} — check the path "
                          "and its permissions") from None
    if len(data) > max_bytes:
        raise ConfigError(f"{where} is larger than {max_bytes // 2**20} MiB — {too_big}")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{where} is not UTF-8 text — save it as UTF-8") from None
    return text, where
