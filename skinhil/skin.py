"""The skin model: the paper's mesh, its parameters and its two mechanics.

Defaults and their reasoning (the paper gives the structure, not SI values):

- ``spacing_m = layer_gap_m = 1e-3``: a millimetre mesh, the scale of fingertip receptor
  spacing; 6x6 masses cover a 5 mm patch.
- ``mass_kg = 1e-4``: an effective nodal mass (tissue plus the load it drags along) that
  puts the mesh's fundamental mode near 100 Hz, in the band where skin vibrations carry
  tactile information, and keeps the fastest mode well inside the real-time step.
- ``stiffness_n_per_m = 50``: a 0.5 N touch then deflects the surface by about a
  millimetre, as fingertip skin does under a light press; that is a large deformation of the
  mesh, which is why both mechanics exist.
- ``damping_n_s_per_m = 0.05``: a damping ratio of about 0.35 for the fundamental mode, so
  forces ring briefly after onset and decay within ~10 ms after the indentation.
- ``tension_n = 0``: no baseline tension by default (the paper's K has none); set it to give
  in-plane springs transverse stiffness ``T/L``.
- ``mechanics = "linear"``: the paper's stiffness-matrix model, so the reproduction starts
  from the paper's own equations; exact at any step and the cheapest. ``"geometric"`` keeps
  true spring lengths for large deformations; the reproduction reports both.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from skinhil.errors import ConfigError
from skinhil.geometry import N_MASSES, N_SPRINGS, build_mesh
from skinhil.mechanics_geometric import GeometricMechanics, max_stable_dt
from skinhil.mechanics_linear import LinearMechanics
from skinhil.stimuli import Stimulus

Mechanics = Literal["linear", "geometric"]


@dataclass(frozen=True)
class SkinParams:
    """Mechanical parameters, identical for every mass and spring (SI units in the names)."""

    mass_kg: float = 1e-4
    stiffness_n_per_m: float = 50.0
    damping_n_s_per_m: float = 0.05
    tension_n: float = 0.0
    spacing_m: float = 1e-3
    layer_gap_m: float = 1e-3
    mechanics: Mechanics = "linear"

    def __post_init__(self) -> None:
        positive = ("mass_kg", "stiffness_n_per_m", "spacing_m", "layer_gap_m")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ConfigError(f"SkinParams.{name} must be a finite number > 0, got {value!r}")
        for name in ("damping_n_s_per_m", "tension_n"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"SkinParams.{name} must be a finite number >= 0, got {value!r}")
        if self.mechanics not in ("linear", "geometric"):
            raise ConfigError(f"SkinParams.mechanics must be 'linear' or 'geometric', "
                              f"got {self.mechanics!r}")


class SkinStepper(Protocol):
    """Fixed-step mechanics for real time: both mechanics provide this."""

    dt_s: float

    def reset(self) -> None:
        """Back to rest."""

    def advance(self, forces_n: np.ndarray) -> np.ndarray:
        """(n, 77, 3) external forces (N) held per step → (n, 338) spring forces (N)."""
        ...

    def simulate_batch(self, inputs: np.ndarray) -> np.ndarray:
        """(n_stim, n_steps, 77, 3) N from rest → (n_stim, n_steps, 338) N; ends at rest."""
        ...


class SkinModel:
    """The 3-layer mass-spring-damper skin (see :mod:`skinhil.geometry` for the numbering).

    Attributes: ``springs`` (338, 2) 0-based mass indices, ``positions`` (77, 3) m, ``fixed``
    (77,) bool, ``params``.
    """

    def __init__(self, params: SkinParams | None = None) -> None:
        self.params = params or SkinParams()
        p = self.params
        self.mesh = build_mesh(p.spacing_m, p.layer_gap_m)
        self.springs = self.mesh.springs
        self.positions = self.mesh.positions
        self.fixed = self.mesh.fixed
        self.n_springs = N_SPRINGS
        self.n_masses = N_MASSES

    def max_dt_s(self) -> float:
        """Largest step (s) the chosen mechanics accepts (inf for the exact linear ZOH)."""
        if self.params.mechanics == "linear":
            return math.inf
        p = self.params
        return max_stable_dt(self.mesh, p.mass_kg, p.stiffness_n_per_m, p.damping_n_s_per_m,
                             p.tension_n)

    def stepper(self, dt_s: float) -> SkinStepper:
        """A fresh fixed-step stepper at rest for real-time block stepping at ``dt_s`` (s)."""
        if not (isinstance(dt_s, int | float) and math.isfinite(dt_s) and dt_s > 0):
            raise ConfigError(f"dt_s must be a finite number of seconds > 0, got {dt_s!r}")
        limit = self.max_dt_s()
        if dt_s > limit:
            raise ConfigError(
                f"dt_s={dt_s:g} s is too large for the geometric mechanics (RK4 is stable "
                f"below {limit:.3g} s with these parameters); lower dt_s or use "
                "mechanics='linear'")
        p = self.params
        cls = LinearMechanics if p.mechanics == "linear" else GeometricMechanics
        return cls(self.mesh, p.mass_kg, p.stiffness_n_per_m, p.damping_n_s_per_m,
                   p.tension_n, float(dt_s))

    def _check_stimulus(self, stimulus: Stimulus) -> None:
        on_fixed = [m for m in stimulus.forces if self.fixed[m - 1]]
        if on_fixed:
            free = ", ".join(f"M{i + 1}" for i in self.mesh.free)
            raise ConfigError(f"stimulus {stimulus.name!r} pushes fixed mass(es) "
                              f"{', '.join(f'M{m}' for m in on_fixed)}, which cannot move; "
                              f"use free masses: {free}")

    def simulate_many(self, stimuli: Sequence[Stimulus], duration_s: float,
                      dt_s: float = 1e-4) -> np.ndarray:
        """Spring forces (N) for each stimulus from rest: (n_stim, n_steps, 338).

        ``n_steps = round(duration_s / dt_s)``; row ``k`` is the force at ``t = k·dt_s``; the
        stimulus is sampled at the start of each step and held over it (zero-order hold).
        """
        if not (isinstance(duration_s, int | float) and math.isfinite(duration_s)
                and duration_s > 0):
            raise ConfigError(f"duration_s must be a finite number of seconds > 0, "
                              f"got {duration_s!r}")
        stepper = self.stepper(dt_s)
        n_steps = max(1, int(round(duration_s / dt_s)))
        t = np.arange(n_steps) * dt_s
        for s in stimuli:
            self._check_stimulus(s)
        inputs = np.stack([s.force_at(t) for s in stimuli]) if stimuli else np.zeros(
            (0, n_steps, N_MASSES, 3))
        return stepper.simulate_batch(inputs)

    def simulate(self, stimulus: Stimulus, duration_s: float, dt_s: float = 1e-4) -> np.ndarray:
        """Spring forces (N) for one stimulus from rest: (n_steps, 338); see simulate_many."""
        return self.simulate_many([stimulus], duration_s, dt_s)[0]
