"""The skin model: the paper's mesh at any size, its parameters, its two mechanics and what
each spring reports.

Defaults and their reasoning (the paper gives the structure, not SI values):

- ``spacing_m = layer_gap_m = 1e-3``: a millimetre mesh, the scale of fingertip receptor
  spacing; 6x6 masses cover a 5 mm patch.
- ``mass_kg = 1e-2``, ``stiffness_n_per_m = 5000``, ``damping_n_s_per_m = 5``: a skin in
  a physically plausible regime, the ``small`` amplitude of the reproduction
  (docs/figures/REPORT.md): the paper's touches (0.5 N on a mass) take its springs to at
  most ~3 % strain (3.2 % under the paper's inputs and the nine Figure 4 conditions,
  geometric mechanics), inside :data:`STRAIN_BOUND` (10 %). Its mesh has the paper regime's
  modes (fundamental near 100 Hz, in the band where skin vibrations carry tactile
  information), damping ratios (about 0.35 for the fundamental: forces ring briefly after
  onset and decay within ~10 ms after the indentation) and, in the linear model, spring
  forces: mass, stiffness and damping are the paper regime's x100, which divides every
  displacement, so every strain, by 100 and leaves the real-time step's stability where it
  was. Why a bound, and 10 %: the paper's model is linear (its eqs. 2-8, the
  small-displacement limit of the true spring lengths), and it departs from the geometric
  mechanics with the length readout by about the strain itself (the largest force gap over
  the paper's inputs and the nine conditions, relative to the largest force: 1 % at 1 %
  strain, 3 % at 3 %, 10 % at 10 %, 40 % at 36 %, 270 % at 200 %;
  ``benchmarks/strain_bound.py``), so below 10 % the paper's
  equations describe the skin they model within 10 %; soft tissue and skin elastomers are
  near-linear only over small strains too (skin's J-shaped stress-strain curve stiffens
  beyond). The paper regime (``SkinParams.at_amplitude("paper")``, ``--amplitude paper``: M
  0.1 g, K 50 N/m, C 0.05 N·s/m, a 0.5 N touch deflecting the surface by about a millimetre)
  takes the same touches to 150-400 % strain, where the paper's PCA claims 1E-F, 2B, 3F and
  4G are reproduced and the small amplitude reproduces 2A and 2C only (REPORT.md): it stays
  one option away.
- ``tension_n = 0``: no baseline tension by default (the paper's K has none); set it to give
  in-plane springs transverse stiffness ``T/L``.
- ``mechanics = "auto"``: the geometric mechanics up to ``AUTO_GEOMETRIC_MAX_SPRINGS``
  (1,210: a 10x10 top layer) springs, the linear one above; one rule, printed in the banner
  of ``serve`` and ``demo`` (``SkinParams.describe_mechanics``). Chosen from the
  reproduction and the board's real-time budget. Reproduction (``skinhil reproduce``,
  docs/figures/REPORT.md, both readouts of both mechanics): the geometric dynamics with the
  length readout reproduce 4 of the paper's 7 checked claims (1E-F, 2A, 3F, 4G), as many as
  the linear dynamics with it (2A, 2C, 3F, 4G) and twice the linear dynamics with the
  axial readout (2); the geometric is the one that stays a faithful model at the paper's forces:
  1E-F, which only the dynamics change, fails on the linear dynamics with either readout,
  and there the mesh moves 4-5 rest lengths, far outside the small displacements its
  stiffness matrix assumes (REPORT.md, "Regime"). Budget: the geometric mechanics costs a
  few times the linear one per spring and step (RK4, spring by spring, the springs between
  fixed masses skipped); with the neurons
  the geometric skin takes about a third of a core at 10x10, so the board keeps real time
  there with room for its encoder and link, and above it the linear mechanics (exact, then
  leapfrog) carries the board beyond a whole hand's 17,000 sensors on one core
  (``benchmarks/bench_size.py``; the figures on the docs' Benchmarks page).
  ``"linear"`` and ``"geometric"`` force one; the geometric one refuses steps above its
  stability limit (~0.14 ms at the defaults).
- ``readout = "length"``: every spring reports ``k·(|L0·e + q_j − q_i| − L0)``, its length
  change, in both mechanics (the paper's Hooke's law on "the rate of change from its
  equilibrium position"); ``"axial"``, ``k·eᵀ(q_j − q_i)``, is its small-displacement limit,
  kept as an explicit option (:mod:`skinhil.model.mechanics.readout`).
- ``size = (6, 6)``: the paper's top layer; any ``rows x cols`` >= 3x3 builds the same
  pyramid (:mod:`skinhil.model.geometry`).
- ``linear_stepper = "auto"``: how the linear mechanics is stepped, one rule: the exact ZOH
  (:mod:`skinhil.model.mechanics.linear`: per-mode when there is no tension) while the mesh has at
  most ``EXACT_MAX_FREE_DOFS`` (200) free degrees of freedom — every top layer up to 8x8,
  the paper's 6x6 (75) among them, whose results are exact at any step — and the
  second-order leapfrog of :mod:`skinhil.model.mechanics.leapfrog` above it, whose step costs
  O(springs) where the exact one costs O(dof²) per step and O(dof³) to set up (at 16x16,
  1,095 free degrees of freedom, a dense step would cost ~20x a leapfrog step). ``"exact"``
  or ``"leapfrog"`` force one regime (the exact one needs dense matrices: fine to a few
  thousand degrees of freedom offline).

The geometric mechanics is stepped spring by spring (O(springs) per step) at every size.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import ClassVar, Literal, Protocol

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import (
    PAPER_SIZE,
    MeshSize,
    build_mesh,
    check_size,
    format_size,
    spring_count,
)
from skinhil.model.mechanics.geometric import GeometricMechanics, max_stable_dt
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics
from skinhil.model.mechanics.linear import LinearMechanics
from skinhil.model.mechanics.readout import READOUTS, Readout
from skinhil.model.stimuli import Schedule, Stimulus
from skinhil.validation import (
    Constraints,
    StrOptions,
    check_param,
    non_negative,
    positive,
    validate_params,
)

Mechanics = Literal["auto", "linear", "geometric"]
Dynamics = Literal["linear", "geometric"]
LinearStepper = Literal["auto", "exact", "leapfrog"]

MODEL_SUMMARY = ("3-layer mass-spring-damper skin, one stochastic Izhikevich neuron per "
                 "spring (skinhil)")
"""The model in one line, as lab outputs name it (NWB's subject and device, LSL's
``acquisition/model``)."""

INPUT_BLOCK_STEPS = 1000
"""Steps of input forces built at a time by :meth:`SkinModel.simulate_many` (bounded memory
at any mesh size)."""
AUTO_GEOMETRIC_MAX_SPRINGS = 1210
"""``mechanics="auto"``: the geometric mechanics up to this many springs (a 10x10 top layer),
the linear one above (module docstring)."""
STRAIN_BOUND = 0.1
"""The strain (a fraction) a physically plausible skin stays within: where the paper's linear
model agrees with the true spring lengths within about as much (module docstring, ``mass_kg``);
the default skin reaches ~3 % under the paper's touches."""
AMPLITUDES: dict[str, float] = {"small": 1.0, "paper": 0.01}
"""The skin's amplitude regimes: :class:`SkinParams`' default mass, stiffness and damping
multiplied together by this factor (:meth:`SkinParams.at_amplitude`). ``"small"``: the
default, a touch of 0.5 N at ~3 % strain; ``"paper"``: the paper's regime, the same modes,
damping ratios and linear spring forces with every displacement x100 (150-400 % strain).
The reproduction runs both (docs/reproduce.md)."""
DEFAULT_AMPLITUDE = "small"
"""The amplitude of ``SkinParams()``."""
EXACT_MAX_FREE_DOFS = 200
"""Above this many free degrees of freedom the linear mechanics is stepped by the leapfrog
(``linear_stepper="auto"``, module docstring); 6x6 has 75, 8x8 183, 9x9 258."""


@dataclass(frozen=True)
class SkinParams:
    """Mechanical parameters, identical for every mass and spring (SI units in the names)."""

    mass_kg: float = 1e-2
    stiffness_n_per_m: float = 5000.0
    damping_n_s_per_m: float = 5.0
    tension_n: float = 0.0
    spacing_m: float = 1e-3
    layer_gap_m: float = 1e-3
    mechanics: Mechanics = "auto"
    """"auto" (geometric up to :data:`AUTO_GEOMETRIC_MAX_SPRINGS` springs, linear above),
    "linear" or "geometric" (module docstring); :attr:`dynamics` says which one runs."""
    size: MeshSize = PAPER_SIZE
    """Top layer (rows, cols) in masses; the layers below follow the pyramid rule."""
    linear_stepper: LinearStepper = "auto"
    """How the linear mechanics is stepped (module docstring)."""
    readout: Readout = "length"
    """What each spring reports, in both mechanics: ``"length"``, ``k·(|L0·e + q_j − q_i| −
    L0)`` (N), or ``"axial"``, its small-displacement limit ``k·eᵀ(q_j − q_i)``
    (:mod:`skinhil.model.mechanics.readout`)."""

    _parameter_constraints: ClassVar[Constraints] = {
        "mass_kg": positive("kg"),
        "stiffness_n_per_m": positive("N/m"),
        "damping_n_s_per_m": non_negative("N·s/m"),
        "tension_n": non_negative("N"),
        "spacing_m": positive("m"),
        "layer_gap_m": positive("m"),
        "mechanics": StrOptions(("auto", "linear", "geometric")),
        "linear_stepper": StrOptions(("auto", "exact", "leapfrog")),
        "readout": StrOptions(READOUTS),
    }

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", check_size(self.size))
        validate_params(self)

    def scaled(self, factor: float) -> SkinParams:
        """These parameters with mass, stiffness and damping multiplied by ``factor``: the same
        modes, damping ratios and linear spring forces, every displacement divided by it."""
        return replace(self, mass_kg=self.mass_kg * factor,
                       stiffness_n_per_m=self.stiffness_n_per_m * factor,
                       damping_n_s_per_m=self.damping_n_s_per_m * factor)

    @classmethod
    def at_amplitude(cls, amplitude: str = DEFAULT_AMPLITUDE, **kwargs: object) -> SkinParams:
        """``SkinParams(**kwargs)`` at ``amplitude`` (:data:`AMPLITUDES`: ``"small"``, the
        default, or ``"paper"``, the paper's regime: M 0.1 g, K 50 N/m, C 0.05 N·s/m)."""
        if amplitude not in AMPLITUDES:
            raise ConfigError(f"unknown amplitude {amplitude!r}; use one of "
                              f"{', '.join(AMPLITUDES)}")
        return cls(**kwargs).scaled(AMPLITUDES[amplitude])  # type: ignore[arg-type]

    @property
    def dynamics(self) -> Dynamics:
        """The mechanics that steps this skin: ``mechanics`` itself, or for ``"auto"`` the
        geometric one up to :data:`AUTO_GEOMETRIC_MAX_SPRINGS` springs and the linear one
        above (module docstring)."""
        if self.mechanics != "auto":
            return self.mechanics
        return ("geometric" if spring_count(self.size) <= AUTO_GEOMETRIC_MAX_SPRINGS
                else "linear")

    def describe_mechanics(self) -> str:
        """One line for banners: the mechanics, how ``auto`` chose it, and the readout."""
        how: str = self.dynamics
        if self.mechanics == "auto":
            rule = (f"auto: geometric up to {AUTO_GEOMETRIC_MAX_SPRINGS} springs, linear above; "
                    f"{spring_count(self.size)} here")
            how = f"{how} ({rule})"
        return f"{how}, {self.readout} readout"


class SkinStepper(Protocol):
    """Fixed-step mechanics, compiled: every stepper provides this (offline and real time)."""

    dt_s: float

    def reset(self) -> None:
        """Back to rest."""

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """(n, n_masses, 3) external forces (N) held per step → (n, n_springs) spring forces
        (N)."""
        ...

    def displacement_m(self) -> np.ndarray:
        """Every mass's displacement from rest now (n_masses, 3) m; fixed masses 0."""
        ...



class SkinModel:
    """The 3-layer mass-spring-damper skin (see :mod:`skinhil.model.geometry` for the numbering).

    Attributes: ``springs`` (n_springs, 2) 0-based mass indices, ``positions`` (n_masses, 3)
    m, ``fixed`` (n_masses,) bool, ``size`` (rows, cols) of the top layer, ``params``; at the
    default 6x6, 338 springs and 77 masses.
    """

    def __init__(self, params: SkinParams | None = None) -> None:
        self.params = params or SkinParams()
        p = self.params
        self.size: MeshSize = p.size
        self.mesh = build_mesh(p.spacing_m, p.layer_gap_m, p.size)
        self.springs = self.mesh.springs
        self.positions = self.mesh.positions
        self.fixed = self.mesh.fixed
        self.n_springs = int(self.springs.shape[0])
        self.n_masses = int(self.positions.shape[0])

    @property
    def linear_regime(self) -> Literal["exact", "leapfrog"]:
        """How the linear mechanics is stepped at this size (module docstring)."""
        if self.params.linear_stepper != "auto":
            return self.params.linear_stepper
        return "exact" if 3 * self.mesh.free.size <= EXACT_MAX_FREE_DOFS else "leapfrog"

    def regime_for(self, state_forces: bool) -> Literal["exact", "leapfrog"]:
        """:attr:`linear_regime`, or with ``state_forces`` (a force that depends on the
        state, as a contact's) the leapfrog: the exact ZOH holds a force known before the
        step, so it cannot carry one; forcing ``"exact"`` then is refused in one line."""
        if not state_forces:
            return self.linear_regime
        if self.params.linear_stepper == "exact":
            raise ConfigError("the exact linear discretisation (ZOH) holds a force known "
                              "before each step and cannot carry a contact, whose force "
                              "depends on where the surface is: use linear_stepper "
                              "'leapfrog' or 'auto', or the geometric mechanics")
        return "leapfrog"

    def max_dt_s(self) -> float:
        """Largest step (s) the chosen mechanics accepts (inf for the linear mechanics: exact
        ZOH, or leapfrog substeps chosen for stability)."""
        if self.params.dynamics == "linear":
            return math.inf
        p = self.params
        return max_stable_dt(self.mesh, p.mass_kg, p.stiffness_n_per_m, p.damping_n_s_per_m,
                             p.tension_n)

    def stepper(self, dt_s: float, state_forces: bool = False) -> SkinStepper:
        """A fresh fixed-step stepper at rest for real-time block stepping at ``dt_s`` (s);
        ``state_forces``: one that can carry a force depending on the state (a contact's):
        the geometric mechanics or the leapfrog (:meth:`regime_for`)."""
        check_param("dt_s", dt_s, positive("s"))
        limit = self.max_dt_s()
        if dt_s > limit:
            raise ConfigError(
                f"dt_s={dt_s:g} s is too large for the geometric mechanics (RK4 is stable "
                f"below {limit:.3g} s with these parameters); lower dt_s or use "
                "mechanics='linear'")
        p = self.params
        cls: type[LinearMechanics | LeapfrogMechanics | GeometricMechanics] = (
            GeometricMechanics if p.dynamics == "geometric" else
            LinearMechanics if self.regime_for(state_forces) == "exact" else LeapfrogMechanics)
        return cls(self.mesh, p.mass_kg, p.stiffness_n_per_m, p.damping_n_s_per_m,
                   p.tension_n, float(dt_s), p.readout)

    def check_stimulus(self, stimulus: Stimulus) -> None:
        """:class:`ConfigError` unless ``stimulus`` is defined on this size and pushes only
        free masses."""
        if stimulus.size != self.size:
            raise ConfigError(f"stimulus {stimulus.name!r} is defined on a "
                              f"{format_size(stimulus.size)} skin, this one is "
                              f"{format_size(self.size)}: define it for "
                              f"{format_size(self.size)} (built-ins: "
                              "skinhil.model.stimuli.at_size)")
        on_fixed = [m for m in stimulus.forces if self.fixed[m - 1]]
        if on_fixed:
            free = ", ".join(f"M{i + 1}" for i in self.mesh.free)
            raise ConfigError(f"stimulus {stimulus.name!r} pushes fixed mass(es) "
                              f"{', '.join(f'M{m}' for m in on_fixed)}, which cannot move; "
                              f"use free masses: {free}")

    def check_schedule(self, schedule: Schedule) -> None:
        """:meth:`check_stimulus` for every distinct stimulus of ``schedule``."""
        for stim in {id(e.stimulus): e.stimulus for e in schedule.entries}.values():
            self.check_stimulus(stim)

    def simulate_many(self, stimuli: Sequence[Stimulus], duration_s: float,
                      dt_s: float = 1e-4) -> np.ndarray:
        """Spring forces (N) for each stimulus from rest: (n_stim, n_steps, n_springs).

        ``n_steps = round(duration_s / dt_s)``; row ``k`` is the force at ``t = k·dt_s``; the
        stimulus is sampled at the start of each step and held over it (zero-order hold).
        """
        check_param("duration_s", duration_s, positive("s"))
        stepper = self.stepper(dt_s)
        n_steps = max(1, int(round(duration_s / dt_s)))
        t = np.arange(n_steps) * dt_s
        for s in stimuli:
            self.check_stimulus(s)
        out = np.empty((len(stimuli), n_steps, self.n_springs))
        for i, s in enumerate(stimuli):  # one stimulus at a time, the input in blocks
            stepper.reset()
            for start in range(0, n_steps, INPUT_BLOCK_STEPS):
                block = t[start:start + INPUT_BLOCK_STEPS]
                out[i, start:start + block.size] = stepper.advance(s.force_at(block))
        stepper.reset()
        return out

    def simulate(self, stimulus: Stimulus, duration_s: float, dt_s: float = 1e-4) -> np.ndarray:
        """Spring forces (N) for one stimulus from rest: (n_steps, n_springs); see
        simulate_many."""
        return self.simulate_many([stimulus], duration_s, dt_s)[0]
