"""A suite's parts as data: the tasks a case poses, the trials a seed draws, a case (its
generator), a suite (its cases, version and seed ranges)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.skin import SkinParams
from skinhil.plant import GraspParams
from skinhil.plant.lifts import LiftScene
from skinhil.world.scenario_file import Scenario


@dataclass(frozen=True)
class PosedTask:
    """A task a case poses: its name (the task registry's), the tolerance of a right answer
    in ``unit`` (None: the task has none) and its classes (a class task's values)."""

    name: str
    tolerance: float | None = None
    unit: str = ""
    classes: tuple[float, ...] = ()


@dataclass(frozen=True)
class Trials:
    """What a case draws for a seed: the scenario the board plays (stimuli and contacts),
    the held object's parameters (None without one), the tasks posed and the run's length
    (s of board time, the scenario and its tail)."""

    suite: str
    case: str
    seed: int
    scenario: Scenario
    grasp: GraspParams | None
    tasks: tuple[PosedTask, ...]
    duration_s: float

    def description(self) -> dict[str, Any]:
        """Every drawn value, as JSON-ready data (floats exact): what :meth:`digest` hashes."""
        entries = [[e.start_s, e.stimulus_id, e.stimulus.name,
                    sorted([m, list(v)] for m, v in e.stimulus.forces.items())]
                   for e in self.scenario.schedule.entries]
        scene = self.scenario.scene
        contacts = [] if scene is None else [
            [c.name, c.start_s, c.indenter.code, c.indenter.geometry().tolist(),
             c.trajectory.keyframes.tolist(), c.trajectory.normal, c.trajectory.tangential,
             c.trajectory.vibration_amplitude_m, c.trajectory.vibration_frequency_hz,
             c.trajectory.vibration_axis, c.mu_static, c.mu_kinetic]
            for c in scene.contacts]
        lifts = ([dataclasses.astuple(lift) for lift in scene.lifts]
                 if isinstance(scene, LiftScene) else [])
        return {"suite": self.suite, "case": self.case, "seed": self.seed,
                "stimuli": entries, "contacts": contacts, "lifts": lifts,
                "grasp": None if self.grasp is None else dataclasses.astuple(self.grasp),
                "tasks": [dataclasses.astuple(t) for t in self.tasks],
                "duration_s": self.duration_s}

    def digest(self) -> str:
        """sha256 (hex) of :meth:`description`: the frozen trials of this seed."""
        text = json.dumps(self.description(), sort_keys=True, allow_nan=True)
        return hashlib.sha256(text.encode()).hexdigest()


Draw = Callable[[np.random.Generator, int, MeshSize, float], tuple[Scenario, GraspParams | None]]
"""A case's generator: (rng, trials, skin size, spacing m) -> the scenario and the held
object's parameters."""


@dataclass(frozen=True)
class Case:
    """A case of a suite: its name, what it plays (one line), the tasks it poses, its
    trial count, the board time (s) after the last trial before the run ends, its
    generator, and whether it holds an object."""

    name: str
    about: str
    tasks: tuple[PosedTask, ...]
    trials: int
    tail_s: float
    draw: Draw
    held_object: bool = False

    def rng(self, seed: int) -> np.random.Generator:
        """The case's generator of seed ``seed``: a numpy Generator seeded from the seed and
        the case's name, so cases of one seed draw independently."""
        if not (isinstance(seed, int) and seed >= 0):
            raise ConfigError(f"a suite seed is a whole number >= 0, got {seed!r}")
        return np.random.default_rng([seed, *self.name.encode()])

    def generate(self, suite: str, seed: int, size: MeshSize = PAPER_SIZE,
                 spacing_m: float = SkinParams.spacing_m, trials: int | None = None) -> Trials:
        """The trials of seed ``seed`` on a skin of top-layer ``size`` and ``spacing_m`` (m);
        ``trials`` lowers the trial count (a shorter run of the same draws' rule)."""
        n = self.trials if trials is None else trials
        if not 1 <= n <= self.trials:
            raise ConfigError(f"case {self.name!r} plays 1..{self.trials} trials, got {n!r}")
        scenario, grasp = self.draw(self.rng(seed), n, size, spacing_m)
        return Trials(suite, self.name, seed, scenario, grasp, self.tasks,
                      scenario.duration_s + self.tail_s)


@dataclass(frozen=True)
class Suite:
    """A versioned suite: ``name-vVERSION``, its cases, the seeds for training and the seeds
    an evaluation draws (disjoint ranges)."""

    name: str
    version: int
    about: str
    cases: tuple[Case, ...]
    training_seeds: range
    evaluation_seeds: range

    def __post_init__(self) -> None:
        a, b = self.training_seeds, self.evaluation_seeds
        if max(a.start, b.start) < min(a.stop, b.stop):
            raise ConfigError(f"suite {self.id}: training and evaluation seeds overlap")

    @property
    def id(self) -> str:
        """``name-vVERSION``: what ``--suite`` names."""
        return f"{self.name}-v{self.version}"

    def case(self, name: str) -> Case:
        """The case ``name``; refused with the cases' names if there is none."""
        for c in self.cases:
            if c.name == name:
                return c
        raise ConfigError(f"suite {self.id} has no case {name!r}: give one of "
                          f"{', '.join(c.name for c in self.cases)}")
