"""``tactile-v1``: six cases whose trials come from the seed (docs/suites.md).

Frozen: every constant and generator below is part of the version; a test pins the digest
of the trials of a few seeds per case (tests/test_suites.py). Any change makes a new
version (a new module, ``tactile-v2``), never an edit here.

Seeds: :data:`TRAINING_SEEDS` are for fitting and training decoders (``dataset``);
``bench --suite`` draws its seeds from :data:`EVALUATION_SEEDS` only.
"""

from __future__ import annotations

import numpy as np

from skinhil.model.geometry import MeshSize
from skinhil.model.stimuli import (
    Schedule,
    ScheduledStimulus,
    at_size,
    direction_conditions,
)
from skinhil.plant import GraspParams
from skinhil.plant.lifts import Lift, drawn_lift_scene
from skinhil.suites import draws
from skinhil.suites.case import Case, PosedTask, Suite
from skinhil.world import Contact, Indenter, Scene, Trajectory
from skinhil.world.scenario_file import Scenario

TRAINING_SEEDS = range(0, 1_000_000)
"""Seeds for training and calibration."""
EVALUATION_SEEDS = range(1_000_000, 2**31)
"""Seeds ``bench --suite`` may draw; none of them is a training seed."""

TOLERANCE_MM = 0.5
"""A LOCATION is right within this distance (mm) of the contact's centroid."""
TOLERANCE_N = 0.05
"""A FORCE is right within this much (N) of the contact's normal force."""
VIBRATION_CLASSES_HZ = (50.0, 100.0, 200.0, 300.0)
"""The vibration frequencies (Hz) drawn, and the classes a VIBRATION answer is judged in."""
LEAD_S = (0.1, 0.3)
"""The first trial's onset (s), drawn in this range."""
TAIL_S = 0.3
"""Board time (s) after the last trial before the run ends (the last answers' window)."""
_EMPTY = Schedule(())


def _contacts(contacts: list[Contact]) -> tuple[Scenario, None]:
    return Scenario(_EMPTY, Scene(tuple(contacts))), None


def _classification(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
                    ) -> tuple[Scenario, None]:
    """The paper's 9 direction conditions on M15 (moved to the skin's size), drawn uniformly;
    a rest of 0.15-0.35 s after each."""
    conditions = [at_size(s, size) for s in direction_conditions()]
    picks = rng.integers(0, len(conditions), size=n)
    starts = draws.onsets_s(rng, [conditions[int(p)].end_s for p in picks], LEAD_S,
                            (0.15, 0.35))
    entries = tuple(ScheduledStimulus(float(t), conditions[int(p)], int(p))
                    for t, p in zip(starts, picks, strict=True))
    return Scenario(Schedule(entries), None), None


def _localisation(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
                  ) -> tuple[Scenario, None]:
    """Presses of a 3 mm sphere with 0.5 N for 0.1 s at places over the inner area."""
    probe = Indenter("sphere", 3e-3)
    places = draws.places_m(rng, n, size, spacing_m)
    traj = [Trajectory.press(float(x), float(y), 0.5, 0.01, 0.1, load=True) for x, y in places]
    starts = draws.onsets_s(rng, [t.duration_s for t in traj], LEAD_S, (0.3, 0.6))
    return _contacts([Contact(probe, t, float(s), name=f"press{i + 1}")
                      for i, (t, s) in enumerate(zip(traj, starts, strict=True))])


def _force(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
           ) -> tuple[Scenario, None]:
    """Presses of a 3 mm sphere at the centre, 0.2-0.8 N, held 0.15 s."""
    probe = Indenter("sphere", 3e-3)
    loads = draws.uniform(rng, n, 0.2, 0.8)
    traj = [Trajectory.press(0.0, 0.0, float(f), 0.01, 0.15, load=True) for f in loads]
    starts = draws.onsets_s(rng, [t.duration_s for t in traj], LEAD_S, (0.3, 0.6))
    return _contacts([Contact(probe, t, float(s), name=f"press{i + 1}")
                      for i, (t, s) in enumerate(zip(traj, starts, strict=True))])


def _slip(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
          ) -> tuple[Scenario, None]:
    """A 5 mm ball held by 1 N, sticking for 0.05-0.25 s, then dragged 2 mm along x across
    the centre at 5-40 mm/s (log-uniform) with low friction: the slip's onset and speed
    drawn."""
    ball = Indenter("sphere", 5e-3)
    dwell = draws.uniform(rng, n, 0.05, 0.25)
    speed = draws.log_uniform(rng, n, 5e-3, 40e-3)
    traj = [Trajectory.slide((-1e-3, 0.0), (1e-3, 0.0), float(v), 1.0, 0.03, float(d),
                             load=True) for d, v in zip(dwell, speed, strict=True)]
    starts = draws.onsets_s(rng, [t.duration_s for t in traj], LEAD_S, (0.3, 0.6))
    return _contacts([Contact(ball, t, float(s), 0.4, 0.3, f"slide{i + 1}")
                      for i, (t, s) in enumerate(zip(traj, starts, strict=True))])


def _vibration(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
               ) -> tuple[Scenario, None]:
    """A flat 1.5 mm pad pressed 20 µm for 0.3 s at the centre, vibrating 8 µm along z at a
    frequency of :data:`VIBRATION_CLASSES_HZ`."""
    pad = Indenter("flat", 1.5e-3)
    freqs = draws.choices(rng, n, VIBRATION_CLASSES_HZ)
    traj = [Trajectory.press(0.0, 0.0, 2e-5, 0.02, 0.3).with_vibration(8e-6, float(f), "z")
            for f in freqs]
    starts = draws.onsets_s(rng, [t.duration_s for t in traj], LEAD_S, (0.2, 0.4))
    return _contacts([Contact(pad, t, float(s), name=f"vibration{i + 1}")
                      for i, (t, s) in enumerate(zip(traj, starts, strict=True))])


GRASP = GraspParams()
"""The hand and the lifts' phases (docs/grasp.md); the objects are drawn per lift."""
FRAGILE_MASS_KG = (0.02, 0.035)
FRAGILE_BREAK_N = (0.75, 0.95)
"""A light, fragile object: its mass (kg) and break force (N) ranges. Its weight and the
largest pull need at most (0.343 + 0.2) / 0.8 = 0.68 N of grip: below every break force."""
STURDY_MASS_KG = (0.085, 0.11)
STURDY_BREAK_N = (1.7, 1.95)
"""A heavy, sturdy object: its weight alone needs at least 0.834 / 0.8 = 1.04 N of grip,
above every fragile break force; its weight and pull at most 1.6 N, below its break force
and the 2 N grip limit. So no constant grip both holds every sturdy object and spares every
fragile one."""
PULL_N = (0.05, 0.2)
"""The unannounced pull's size (N)."""
GRASP_S = (0.1, 0.3)
"""The hand's closing time before the rise (s)."""


def _grasp(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
           ) -> tuple[Scenario, GraspParams]:
    """Lifts of objects light and fragile or heavy and sturdy (half each, both present from
    two lifts on, in a drawn order), each with its grasp time, break force and an
    unannounced pull of drawn time and size in the hold."""
    kinds = rng.permutation(np.arange(n) % 2)
    grasp_s = draws.uniform(rng, n, *GRASP_S)
    pull_n = draws.uniform(rng, n, *PULL_N)
    latest = GRASP.hold_s - 2 * GRASP.ramp_s - GRASP.pull_s
    pull_at = draws.uniform(rng, n, 0.05, latest)
    frac = rng.uniform(size=(n, 2))
    lo_m, hi_m = np.where(kinds[:, None] == 1, STURDY_MASS_KG, FRAGILE_MASS_KG).T
    lo_b, hi_b = np.where(kinds[:, None] == 1, STURDY_BREAK_N, FRAGILE_BREAK_N).T
    mass = lo_m + frac[:, 0] * (hi_m - lo_m)
    brk = lo_b + frac[:, 1] * (hi_b - lo_b)
    lasts = [GRASP.lift_duration_s(Lift(0.0, 1.0, grasp_s=float(g))) for g in grasp_s]
    starts = draws.onsets_s(rng, lasts, LEAD_S, (0.1, 0.3))
    lifts = [Lift(float(starts[i]), float(mass[i]), float(brk[i]), float(grasp_s[i]),
                  float(pull_n[i]), float(pull_at[i])) for i in range(n)]
    scene = drawn_lift_scene(GRASP, lifts)
    return Scenario(_EMPTY, scene), GRASP


CASES = (
    Case("classification", "the paper's 9 direction conditions (Fig 4) in a drawn order and "
         "drawn rests", (PosedTask("classification", None, "", tuple(range(9))),),
         9, TAIL_S, _classification),
    Case("localisation", "0.5 N presses of a 3 mm sphere at drawn places over the inner area",
         (PosedTask("localisation", TOLERANCE_MM, "mm"),), 8, TAIL_S, _localisation),
    Case("force", "presses of a 3 mm sphere at the centre with drawn forces, 0.2-0.8 N",
         (PosedTask("force", TOLERANCE_N, "N"),), 8, TAIL_S, _force),
    Case("slip", "a 1 N ball dragged 2 mm at 5-40 mm/s after a drawn stick of 0.05-0.25 s",
         (PosedTask("slip"),), 5, TAIL_S, _slip),
    Case("vibration", "a flat pad vibrating at drawn frequencies of 50, 100, 200, 300 Hz",
         (PosedTask("vibration", None, "Hz", VIBRATION_CLASSES_HZ),), 8, TAIL_S, _vibration),
    Case("grasp", "lifts of light fragile and heavy sturdy objects with drawn timing, break "
         "forces and unannounced pulls", (), 4, TAIL_S, _grasp, held_object=True),
)

SUITE = Suite("tactile", 1, "touch tasks whose trials come from the seed", CASES,
              TRAINING_SEEDS, EVALUATION_SEEDS)
