"""Touch stimuli: per-mass force vectors with the paper's time profile, and schedules of them.

Time profile (paper Figure 1D): a stimulus with peak forces ``F_m`` (N, per paper mass number
``m``) applies ``F_m · exp(−(t − onset)/τ)`` for ``onset ≤ t < onset + indentation`` and zero
otherwise: abrupt onset, exponential decay during the indentation phase, nothing after.

Built-in stimuli (documented choices; the paper gives the directions, not every value):

- :func:`paper_stimuli` — Figure 3's five inputs (panels A-E, names "A".."E"), 0.5 N each.
  The paper's text fixes inputs 1-3: input 1 is Figure 1's normal press on M15; inputs 2 and
  3 are the same push on the same mass, differing only in the push's angle against the z axis
  (one perpendicular, one oblique). Inputs 4 and 5 are ours. The set is one factor at a
  time: each input after the first differs from one earlier input in one thing only.

  ===== ===================== ==== ============================================
  input force (N)             mass differs from
  ===== ===================== ==== ============================================
  1 (A) (0, 0, −0.5)          M15  —
  2 (B) (0, 0, −0.5)          M16  input 1 in place (the neighbour at +x)
  3 (C) (0.3536, 0, −0.3536)  M16  input 2 in angle: 45° from −z, tilted to +x
  4 (D) (0.5, 0, 0)           M15  input 1 in direction: tangential (shear), +x
  5 (E) (0, 0.5, 0)           M15  input 4 in shear direction: +y
  ===== ===================== ==== ============================================

  Inputs 2 and 3 push M16, M15's nearest free neighbour in the same row, because a
  perpendicular push on M15 itself would be input 1 again; the oblique angle, 45°, splits
  the push equally into normal and tangential parts, tilted along +x (the row direction).
- :func:`direction_conditions` — Figure 4's 9 indentation conditions: a force in the x-y plane
  on M15 at angles 0°, 120°, 240° (from +x towards +y) and magnitudes 0.1, 0.3, 0.5 N,
  condition index ``3·i_angle + i_magnitude``; these are the classes the decoder learns.
  Their angles and magnitudes are the project's choice (the paper shows its conditions as
  arrows without values); :func:`figure_4a_stimulus` is the one stimulus the paper gives in
  numbers (Fx = Fy = 0.5 N on M15).

All use ``onset_s = 0``, ``indentation_s = 0.25`` and ``decay_tau_s = 0.1`` by default.

Mesh sizes: a :class:`Stimulus` names masses by number on a mesh of a given top-layer size
(``size``, default the paper's 6x6), which validates the numbers; a model takes only stimuli of
its own size (:meth:`skinhil.model.skin.SkinModel.check_stimulus`). The built-in stimuli are defined
on the paper's 6x6 numbering; :func:`at_size` (and
``builtin_catalog(size)``) moves them to another size keeping each pushed mass's place
relative to the centre of its layer: layer, row and column are kept and the row (column) is
shifted by ``trunc((rows − 6)/2)`` (``trunc((cols − 6)/2)``), so M15 (layer 1, row 3, column
3, beside the centre of the 6x6 patch) becomes row 8, column 8 of a 16x16 skin (M120) and row
2, column 2 of a 3x3 skin (M5, its only free top mass). A moved stimulus that lands on a
fixed mass (B and C, on M16, at 3x3) is refused by the model with a clear error.

Schedules place stimuli on a timeline (``start_s`` of each), from code, from
:func:`random_schedule` or from a TOML file (:func:`skinhil.model.schedule_file.load_schedule`,
format and limits in ``docs/schedule.md``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from numbers import Real
from types import MappingProxyType
from typing import ClassVar

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import (
    PAPER_SIZE,
    MeshSize,
    check_size,
    format_size,
    layer_shapes,
    mass_count,
    mass_index,
    mass_position,
)
from skinhil.validation import (
    Constraints,
    Interval,
    check_param,
    non_negative,
    validate_params,
)

DIRECTION_ANGLES_DEG: tuple[float, ...] = (0.0, 120.0, 240.0)
DIRECTION_MAGNITUDES_N: tuple[float, ...] = (0.1, 0.3, 0.5)
PAPER_STIMULUS_ID_BASE = 10
"""Stimulus ids: direction conditions are 0..8, paper stimuli A-E are 10..14."""
USER_STIMULUS_ID_BASE = 100
"""Stimuli defined in a schedule file get ids from 100 on, in file order."""


@dataclass(frozen=True)
class Stimulus:
    """A touch: peak force vectors (N) on numbered masses and the Figure 1D profile.

    ``forces`` maps a 1-based mass number (:mod:`skinhil.model.geometry`) to ``(fx, fy, fz)`` in
    newtons, on a mesh whose top layer is ``size`` (rows, cols) masses.
    ``onset_s`` is when the force starts, ``indentation_s`` how long it lasts and
    ``decay_tau_s`` its exponential decay constant during the indentation.
    """

    name: str
    forces: Mapping[int, tuple[float, float, float]]
    onset_s: float = 0.0
    indentation_s: float = 0.25
    decay_tau_s: float = 0.1
    size: MeshSize = PAPER_SIZE
    """Top-layer (rows, cols) of the mesh the mass numbers refer to."""
    _peak: np.ndarray = field(init=False, repr=False, compare=False)
    _pushed: np.ndarray = field(init=False, repr=False, compare=False)

    _parameter_constraints: ClassVar[Constraints] = {
        "onset_s": non_negative("s"),
        "indentation_s": non_negative("s"),
        "decay_tau_s": Interval(Real, 0, math.inf, closed="right", unit="s",
                                hint="inf: a constant force"),
    }

    def __post_init__(self) -> None:
        size = check_size(self.size)
        n_masses = mass_count(size)
        clean: dict[int, tuple[float, float, float]] = {}
        for mass, vec in self.forces.items():
            try:
                number = int(mass)
            except (TypeError, ValueError):
                raise ConfigError(f"stimulus {self.name!r}: mass {mass!r} is not a number; "
                                  f"use mass numbers 1..{n_masses} of a {format_size(size)} "
                                  "skin") from None
            if not 1 <= number <= n_masses:
                raise ConfigError(f"stimulus {self.name!r}: unknown mass number {number}; "
                                  f"use mass numbers 1..{n_masses} of a {format_size(size)} "
                                  "skin")
            arr = np.asarray(vec, dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise ConfigError(f"stimulus {self.name!r}: force on M{number} must be three "
                                  f"finite numbers (fx, fy, fz) in newtons, got {vec!r}")
            if number in clean:
                arr = arr + np.asarray(clean[number])
            clean[number] = (float(arr[0]), float(arr[1]), float(arr[2]))
        validate_params(self, where=f"stimulus {self.name!r}: ")
        pushed = sorted(m for m, vec in clean.items() if any(x != 0.0 for x in vec))
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "forces", MappingProxyType(clean))
        object.__setattr__(self, "_pushed", np.array([m - 1 for m in pushed], dtype=np.int64))
        object.__setattr__(self, "_peak", np.array([clean[m] for m in pushed],
                                                   dtype=float).reshape(-1, 3))

    @property
    def pushed_masses(self) -> np.ndarray:
        """0-based indices of the masses with a nonzero peak force, ascending."""
        return self._pushed.copy()

    @property
    def peak_forces_n(self) -> np.ndarray:
        """(n_masses, 3) peak force per mass (N), 0-based mass index (77 masses at 6x6)."""
        out = np.zeros((mass_count(self.size), 3))
        out[self._pushed] = self._peak
        return out

    @property
    def end_s(self) -> float:
        """Time (s) at which the force returns to zero."""
        return self.onset_s + self.indentation_s

    def profile(self, t_s: np.ndarray | float) -> np.ndarray:
        """The unitless Figure 1D time profile at times ``t_s`` (s)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        out = np.empty(t.shape)
        _profile_into(out.ravel(), t.ravel(), self.onset_s, self.end_s, self.decay_tau_s)
        return out.reshape(np.shape(t_s))

    def force_at(self, t_s: np.ndarray) -> np.ndarray:
        """Force on every mass at times ``t_s`` (s): (len(t_s), n_masses, 3) N."""
        out = np.zeros((np.shape(t_s)[0], mass_count(self.size), 3))
        self.add_force(t_s, out)
        return out

    def add_force(self, t_s: np.ndarray, out: np.ndarray) -> None:
        """Add the force at times ``t_s`` (s) into ``out`` (len(t_s), n_masses, 3) N."""
        if out.shape[1] != mass_count(self.size):
            raise ConfigError(f"stimulus {self.name!r} is defined on a {format_size(self.size)}"
                              f" skin ({mass_count(self.size)} masses), not on one of "
                              f"{out.shape[1]} masses")
        _add_profiled(out, np.asarray(t_s, dtype=float), 0.0, self._pushed, self._peak,
                      self.onset_s, self.end_s, self.decay_tau_s)


@numba.njit(inline="always")
def _profile_at(t: float, onset: float, end: float, tau: float) -> float:  # pragma: no cover
    # the Figure 1D profile: exp(-(t - onset)/tau) during the indentation, 0 otherwise
    return math.exp(-(t - onset) / tau) if onset <= t < end else 0.0


@numba.njit(cache=True)
def _profile_into(out: np.ndarray, t: np.ndarray, onset: float, end: float,
                  tau: float) -> None:  # pragma: no cover - compiled
    for k in range(t.shape[0]):
        out[k] = _profile_at(t[k], onset, end, tau)


@numba.njit(cache=True)
def _add_profiled(out: np.ndarray, t: np.ndarray, t_shift: float, pushed: np.ndarray,
                  peak: np.ndarray, onset: float, end: float,
                  tau: float) -> None:  # pragma: no cover - compiled
    # out[k, pushed[i]] += peak[i] (N) times the profile at t[k] − t_shift (s)
    for k in range(t.shape[0]):
        scale = _profile_at(t[k] - t_shift, onset, end, tau)
        if scale != 0.0:
            for i in range(pushed.shape[0]):
                for a in range(3):
                    out[k, pushed[i], a] += scale * peak[i, a]


@numba.njit(cache=True)
def add_schedule_forces(out: np.ndarray, t: np.ndarray, starts: np.ndarray,
                        onsets: np.ndarray, ends: np.ndarray, which: np.ndarray,
                        stim_onsets: np.ndarray, stim_ends: np.ndarray, taus: np.ndarray,
                        pushed_ptr: np.ndarray, pushed: np.ndarray,
                        peaks: np.ndarray) -> None:  # pragma: no cover - compiled
    """Add into ``out`` (len(t), n_masses, 3) the force (N) at times ``t`` (s) of every entry whose
    [onset, end) (s) meets [min t, max t], in entry order; entry ``e`` plays stimulus
    ``which[e]``. The arrays after ``t`` are a :attr:`Schedule.kernel_operands`."""
    if t.shape[0] == 0:
        return
    lo = t.min()
    hi = t.max()
    for e in range(starts.shape[0]):
        if onsets[e] <= hi and ends[e] > lo:
            s = which[e]
            lo_i = pushed_ptr[s]
            hi_i = pushed_ptr[s + 1]
            _add_profiled(out, t, starts[e], pushed[lo_i:hi_i], peaks[lo_i:hi_i],
                          stim_onsets[s], stim_ends[s], taus[s])


def paper_stimuli() -> list[Stimulus]:
    """Figure 3's five inputs A-E (inputs 1-5; see the module docstring)."""
    s = 0.5 / math.sqrt(2.0)
    return [
        Stimulus("A", {15: (0.0, 0.0, -0.5)}),
        Stimulus("B", {16: (0.0, 0.0, -0.5)}),
        Stimulus("C", {16: (s, 0.0, -s)}),
        Stimulus("D", {15: (0.5, 0.0, 0.0)}),
        Stimulus("E", {15: (0.0, 0.5, 0.0)}),
    ]


def direction_conditions() -> list[Stimulus]:
    """The 9 indentation conditions of the paper's Figure 4 (see module docstring)."""
    out = []
    for angle in DIRECTION_ANGLES_DEG:
        rad = math.radians(angle)
        for mag in DIRECTION_MAGNITUDES_N:
            vec = (mag * math.cos(rad), mag * math.sin(rad), 0.0)
            out.append(Stimulus(f"{angle:g}deg_{mag:g}N", {15: vec}))
    return out


def figure_4a_stimulus() -> Stimulus:
    """The stimulus drawn in the paper's Figure 4A: Fx = Fy = 0.5 N on M15 (0.71 N at 45°).
    Not one of the 9 decoded conditions (their angles and magnitudes are the project's
    choice, docs/reproduce.md); the report shows its strain and what sensor #5 sees of it."""
    return Stimulus("fig4A_Fx0.5_Fy0.5", {15: (0.5, 0.5, 0.0)})


def at_size(stimulus: Stimulus, size: MeshSize) -> Stimulus:
    """``stimulus`` moved to a mesh of top-layer ``size``, each pushed mass keeping its layer
    and its place relative to the layer's centre (module docstring); itself if the size is
    already ``size``."""
    size = check_size(size)
    if stimulus.size == size:
        return stimulus
    shift_r = int((size[0] - stimulus.size[0]) / 2)
    shift_c = int((size[1] - stimulus.size[1]) / 2)
    moved: dict[int, tuple[float, float, float]] = {}
    for number, vec in stimulus.forces.items():
        layer, row, col = mass_position(number - 1, stimulus.size)
        rows, cols = layer_shapes(size)[layer]
        r, c = row + shift_r, col + shift_c
        if not (0 <= r < rows and 0 <= c < cols):
            raise ConfigError(f"stimulus {stimulus.name!r}: M{number} has no place on a "
                              f"{format_size(size)} skin; define the stimulus for that size")
        moved[mass_index(layer, r, c, size) + 1] = vec
    return Stimulus(stimulus.name, moved, stimulus.onset_s, stimulus.indentation_s,
                    stimulus.decay_tau_s, size)


def builtin_catalog(size: MeshSize = PAPER_SIZE) -> dict[str, tuple[int, Stimulus]]:
    """Every built-in stimulus by name, with its stimulus id (0..8 and 10..14), on a mesh of
    top-layer ``size`` (moved by :func:`at_size`)."""
    cat = {s.name: (i, at_size(s, size)) for i, s in enumerate(direction_conditions())}
    for i, s in enumerate(paper_stimuli()):
        cat[s.name] = (PAPER_STIMULUS_ID_BASE + i, at_size(s, size))
    return cat


MAX_FORCE_N = 100.0
"""Largest force (N) on one component of one mass, of one stimulus and of all the stimuli
that overlap: 200 times the paper's 0.5 N; larger forces tear any real skin and overflow the
model."""


@dataclass(frozen=True)
class ScheduledStimulus:
    """One stimulus on a timeline: it starts ``start_s`` (s) after the schedule's start."""

    start_s: float
    stimulus: Stimulus
    stimulus_id: int

    @property
    def onset_s(self) -> float:
        """Absolute onset time (s) of the force."""
        return self.start_s + self.stimulus.onset_s

    @property
    def end_s(self) -> float:
        """Absolute time (s) at which the force returns to zero."""
        return self.start_s + self.stimulus.end_s


def check_total_force(entries: Sequence[ScheduledStimulus], where: str) -> None:
    """Refuse a timeline whose overlapping stimuli add up to more than :data:`MAX_FORCE_N`
    on one component of one mass, each stimulus counted at its peak from its onset to its
    end: the cap holds for the sum of the presses, not only for each."""
    changes: list[tuple[float, int, int, tuple[float, float, float]]] = []
    for e in entries:
        for mass, vec in e.stimulus.forces.items():
            a = (abs(vec[0]), abs(vec[1]), abs(vec[2]))
            changes.append((e.onset_s, 1, mass, a))
            changes.append((e.end_s, 0, mass, a))  # at one time, ends before starts
    changes.sort(key=lambda c: (c[0], c[1]))
    load: dict[int, list[float]] = {}
    for t, starts, mass, a in changes:
        total = load.setdefault(mass, [0.0, 0.0, 0.0])
        sign = 1.0 if starts else -1.0
        for k in range(3):
            total[k] += sign * a[k]
        if starts and max(total) > MAX_FORCE_N * (1 + 1e-9):
            raise ConfigError(f"{where}: the stimuli overlapping at {t:g} s press mass {mass} "
                              f"with {max(total):g} N in one direction — at most "
                              f"{MAX_FORCE_N:g} N in all; space the events out or lower "
                              "their forces")


ScheduleOperands = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                         np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""``Schedule.kernel_operands``: see :func:`_pack_entries`."""


@dataclass(frozen=True)
class Schedule:
    """A timeline of stimuli (sorted by start); forces of overlapping stimuli add."""

    entries: tuple[ScheduledStimulus, ...]
    kernel_operands: ScheduleOperands = field(init=False, repr=False, compare=False)
    """What the compiled force kernel reads after the output and the times (see
    :func:`_pack_entries`)."""

    def __post_init__(self) -> None:
        ordered = tuple(sorted(self.entries, key=lambda e: e.start_s))
        for e in ordered:
            check_param("start_s", e.start_s, non_negative("s"),
                        where=f"schedule: stimulus {e.stimulus.name!r}: ")
        sizes = {e.stimulus.size for e in ordered}
        if len(sizes) > 1:
            raise ConfigError(f"schedule mixes stimuli of skins of sizes "
                              f"{', '.join(sorted(format_size(z) for z in sizes))}: define "
                              "every stimulus for one size")
        object.__setattr__(self, "entries", ordered)
        object.__setattr__(self, "kernel_operands", _pack_entries(ordered))

    @property
    def duration_s(self) -> float:
        """Time (s) at which the last stimulus ends."""
        return max((e.end_s for e in self.entries), default=0.0)

    @property
    def size(self) -> MeshSize | None:
        """Top-layer size of its stimuli's mesh (None for an empty schedule)."""
        return self.entries[0].stimulus.size if self.entries else None

    def check_size(self, size: MeshSize) -> None:
        """:class:`ConfigError` unless every stimulus is defined on a mesh of ``size``."""
        if self.entries and self.size != size:
            raise ConfigError(f"the schedule's stimuli are defined on a "
                              f"{format_size(self.entries[0].stimulus.size)} skin, not "
                              f"{format_size(size)}: define them for {format_size(size)}")

    def force_at(self, t_s: np.ndarray, size: MeshSize = PAPER_SIZE) -> np.ndarray:
        """Total force on every mass of a mesh of ``size`` at absolute times ``t_s`` (s):
        (len, n_masses, 3) N."""
        self.check_size(size)
        t = np.asarray(t_s, dtype=float)
        out = np.zeros((t.shape[0], mass_count(size), 3))
        add_schedule_forces(out, t, *self.kernel_operands)
        return out


def _pack_entries(entries: Sequence[ScheduledStimulus]) -> ScheduleOperands:
    """The arrays :func:`add_schedule_forces` reads after ``out`` and ``t``: per entry its start,
    onset and end (s) and stimulus index; per distinct stimulus its onset, end and decay
    constant (s), its pushed masses and their peak forces (N) in CSR form: pointers, 0-based
    mass indices, and (n_pushed, 3) peak forces aligned with the indices."""
    index: dict[int, int] = {}
    stims: list[Stimulus] = []
    for e in entries:
        if id(e.stimulus) not in index:
            index[id(e.stimulus)] = len(stims)
            stims.append(e.stimulus)
    counts = [s._pushed.size for s in stims]
    return (np.array([e.start_s for e in entries], dtype=float),
            np.array([e.onset_s for e in entries], dtype=float),
            np.array([e.end_s for e in entries], dtype=float),
            np.array([index[id(e.stimulus)] for e in entries], dtype=np.int64),
            np.array([s.onset_s for s in stims], dtype=float),
            np.array([s.end_s for s in stims], dtype=float),
            np.array([s.decay_tau_s for s in stims], dtype=float),
            np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64),
            np.concatenate([s._pushed for s in stims] + [np.zeros(0, np.int64)]).astype(
                np.int64),
            np.concatenate([s._peak for s in stims] + [np.zeros((0, 3))]))


def random_schedule(stimuli: Sequence[Stimulus], n: int, rest_s: float = 0.25,
                    seed: int | None = 0, ids: Sequence[int] | None = None,
                    lead_s: float = 0.1) -> Schedule:
    """``n`` stimuli drawn uniformly at random (seeded), each followed by ``rest_s`` (s) of rest.

    The first starts at ``lead_s`` (s); ``ids`` gives each stimulus's id (default: its index).
    """
    if not stimuli:
        raise ConfigError("random schedule: no stimuli to choose from")
    if n < 0 or rest_s < 0 or lead_s < 0:
        raise ConfigError("random schedule: n, rest_s and lead_s must be >= 0")
    ids = list(range(len(stimuli))) if ids is None else list(ids)
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(stimuli), size=n)
    entries, t = [], lead_s
    for p in picks:
        stim = stimuli[int(p)]
        entries.append(ScheduledStimulus(t, stim, ids[int(p)]))
        t += stim.end_s + rest_s
    return Schedule(tuple(entries))
