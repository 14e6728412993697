"""Parameter sweeps of the information measures (paper Figure 2): K x C (x tension) grids.

Each grid point builds the skin with that spring stiffness ``K`` (N/m), damping ``C``
(N·s/m) and baseline tension (N), everything else from ``SweepSpec.base``, simulates the 5
paper stimuli (Figure 3 A-E) for both phases (0–0.5 s) and computes the measures of
:mod:`skinhil.analysis.information` on the 338 spring forces. The sweep is deterministic (no
neuron noise enters these measures), so a local run and a Dask run give identical numbers.

Per-point simulation (documented choices):

- ``linear`` mechanics without tension and with the axial readout: the exact modal
  responses of :mod:`skinhil.analysis.modal_response` at ``dt_s = 0.25 ms`` (2 kHz: the
  fastest mode of the default grid's stiffest skin is ~1 kHz, and the exact zero-order hold
  has no step error), ~15 ms per point on one core;
- ``linear`` with the length readout (the default: not linear in the displacements, so no
  reduced basis is exact) or with tension: :meth:`skinhil.SkinModel.simulate_many`, the same
  exact zero-order hold at the same step;
- strain: every point also stores the strain of its runs (``max_strain``, ``median_strain``,
  :func:`skinhil.model.strain.strain_summary`), so each verdict on a sweep says how far the
  springs were taken;
- ``geometric``: :meth:`skinhil.SkinModel.simulate_many`; the
  geometric mechanics' explicit integrator needs ``dt`` below its stability limit, so a point
  uses the largest step ``≤ dt_s`` and ``≤ 0.9 x`` that limit that tiles the 0.25 s phases
  (heavily damped points need ~60 µs steps and cost ~1 s); a point that still diverges
  reports NaN.

Execution: local worker processes (``concurrent.futures``) by default, or a Dask distributed
cluster given its scheduler address; a tqdm bar shows progress. Every point computes with one
BLAS thread (the sweep sets this in each worker process, Dask workers included: a BLAS thread
count changes the rounding, and points are parallel anyway), so results are bit-identical
wherever they ran.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np
from threadpoolctl import threadpool_limits
from tqdm.auto import tqdm

from skinhil.analysis.information import InformationMeasures, information_measures
from skinhil.analysis.modal_response import reduced_responses, supports
from skinhil.analysis.phases import PhaseWindows
from skinhil.errors import ConfigError
from skinhil.model.skin import Mechanics, SkinModel, SkinParams
from skinhil.model.stimuli import Stimulus, at_size, paper_stimuli
from skinhil.model.strain import strain_summary
from skinhil.validation import Constraints, InstanceOf, positive, validate_params
from skinhil.workers import one_blas_thread, process_map, worker_count

logger = logging.getLogger(__name__)

STRAIN: tuple[str, ...] = ("max_strain", "median_strain")
"""The strain of a point's runs (:func:`skinhil.model.strain.strain_summary`), stored beside
its measures."""
MEASURES: tuple[str, ...] = tuple(InformationMeasures.__dataclass_fields__) + STRAIN
"""Names of the values stored per grid point."""
STABILITY_MARGIN = 0.9
"""Fraction of the geometric integrator's stability limit used as the largest step."""


def log_values(low: float, high: float, n: int) -> tuple[float, ...]:
    """``n`` log-spaced values from ``low`` to ``high`` (both included)."""
    if not (0 < low <= high) or n < 1:
        raise ConfigError(f"need 0 < low <= high and n >= 1, got {low}, {high}, {n}")
    return tuple(float(v) for v in np.geomspace(low, high, n))


@dataclass(frozen=True)
class SweepSpec:
    """A sweep grid: ``stiffness_n_per_m`` x ``damping_n_s_per_m`` x ``tension_n`` values, the
    ``mechanics``, the largest step ``dt_s`` (s) and the ``base`` parameters of the rest."""

    stiffness_n_per_m: tuple[float, ...]
    damping_n_s_per_m: tuple[float, ...]
    tension_n: tuple[float, ...] = (0.0,)
    mechanics: Mechanics = "linear"
    dt_s: float = 2.5e-4
    base: SkinParams = field(default_factory=SkinParams)
    timing: tuple[float, float] | None = None
    """(indentation_s, decay_tau_s) of the stimuli (s), or None for the built-in ones'; the
    phases follow the indentation (:meth:`PhaseWindows.of`)."""

    _parameter_constraints: ClassVar[Constraints] = {
        "dt_s": positive("s"),
        "base": InstanceOf(SkinParams, "a skinhil.SkinParams"),
    }

    def __post_init__(self) -> None:
        for name in ("stiffness_n_per_m", "damping_n_s_per_m", "tension_n"):
            values = tuple(float(v) for v in getattr(self, name))
            if not values:
                raise ConfigError(f"SweepSpec.{name} needs at least one value")
            object.__setattr__(self, name, values)
        validate_params(self)
        for p in self.points():  # validates every value through SkinParams
            del p

    @classmethod
    def log_grid(cls, n_stiffness: int, n_damping: int, mechanics: Mechanics = "linear",
                 stiffness_range: tuple[float, float] | None = None,
                 damping_range: tuple[float, float] | None = None,
                 tension_n: Sequence[float] = (0.0,), dt_s: float = 2.5e-4,
                 base: SkinParams | None = None) -> SweepSpec:
        """Log-spaced grid around ``base`` (default ``SkinParams()``); the default ranges
        span a decade either side of its stiffness (N/m) and damping (N·s/m)."""
        base = base or SkinParams()
        k, c = base.stiffness_n_per_m, base.damping_n_s_per_m
        k_range = stiffness_range or (k / 10, k * 10)
        c_range = damping_range or (c / 10, c * 10)
        return cls(log_values(*k_range, n_stiffness), log_values(*c_range, n_damping),
                   tuple(tension_n), mechanics, dt_s, base=base)

    @property
    def shape(self) -> tuple[int, int, int]:
        """(n_tension, n_stiffness, n_damping)."""
        return len(self.tension_n), len(self.stiffness_n_per_m), len(self.damping_n_s_per_m)

    def points(self) -> Iterator[SkinParams]:
        """Skin parameters of every point, tension-major, then stiffness, then damping."""
        for t in self.tension_n:
            for k in self.stiffness_n_per_m:
                for c in self.damping_n_s_per_m:
                    yield replace(self.base, stiffness_n_per_m=k, damping_n_s_per_m=c,
                                  tension_n=t, mechanics=self.mechanics)


@dataclass(frozen=True)
class SweepResult:
    """Measures on the grid: ``values[name]`` has shape ``spec.shape``; ``seconds`` wall time."""

    spec: SweepSpec
    values: dict[str, np.ndarray]
    seconds: float

    def at(self, name: str) -> np.ndarray:
        """(n_stiffness, n_damping) map of measure ``name`` at the first tension."""
        return self.values[name][0]


def point_step(params: SkinParams, dt_s: float, windows: PhaseWindows) -> float:
    """The step (s) a point is simulated at (see module docstring)."""
    if params.dynamics == "linear":
        return dt_s
    limit = STABILITY_MARGIN * SkinModel(params).max_dt_s()
    phase = windows.indentation_s[1] - windows.indentation_s[0]
    return phase / math.ceil(phase / min(dt_s, limit) - 1e-9)


def timed_stimuli(params: SkinParams, timing: tuple[float, float] | None = None
                  ) -> list[Stimulus]:
    """The paper stimuli at the skin's size (:func:`at_size`), with ``timing``
    (indentation_s, decay_tau_s) if given."""
    stimuli = [at_size(s, params.size) for s in paper_stimuli()]
    if timing is not None:
        stimuli = [replace(s, indentation_s=timing[0], decay_tau_s=timing[1]) for s in stimuli]
    return stimuli


def point_values(params: SkinParams, dt_s: float = 2.5e-4,
                 timing: tuple[float, float] | None = None) -> dict[str, float]:
    """Every value of :data:`MEASURES` at one point: the measures of the paper stimuli
    (:func:`timed_stimuli`) and the strain of their runs; NaN if the point diverged."""
    stimuli = timed_stimuli(params, timing)
    windows = PhaseWindows.of(stimuli)
    with threadpool_limits(1):
        step = point_step(params, dt_s, windows)
        if supports(params):
            reduced = reduced_responses(params, stimuli, windows.duration_s, step)
            responses, forces = reduced.reduced, reduced.full_forces()
        else:
            responses = SkinModel(params).simulate_many(stimuli, windows.duration_s, step)
            forces = responses
        if not np.all(np.isfinite(responses)):
            logger.warning("sweep point %s diverged; its measures are NaN", params)
            return dict.fromkeys(MEASURES, math.nan)
        strain = strain_summary(forces, params)
        return {**information_measures(responses, step, windows).as_dict(),
                "max_strain": strain.max, "median_strain": strain.median}


def evaluate_point(params: SkinParams, dt_s: float = 2.5e-4) -> InformationMeasures:
    """Simulate the paper stimuli (moved to the skin's size by :func:`at_size`) with
    ``params`` and return the information measures."""
    values = point_values(params, dt_s)
    return InformationMeasures(**{k: values[k] for k in InformationMeasures.__dataclass_fields__})


def _evaluate(args: tuple[SkinParams, float, tuple[float, float] | None]) -> dict[str, float]:
    return point_values(*args)


def _dask(tasks: list[tuple[SkinParams, float, tuple[float, float] | None]], scheduler: str,
          bar: tqdm, timeout_s: float) -> list:
    try:
        from distributed import Client, as_completed
    except ImportError:  # pragma: no cover - depends on the installation
        raise ConfigError("a Dask scheduler was given but dask.distributed is not installed; "
                          "pip install 'skinhil[dask]'") from None
    try:
        client = Client(scheduler, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    try:
        client.run(one_blas_thread)
        futures = client.map(_evaluate, tasks, pure=False)
        for _ in as_completed(futures):
            bar.update()
        return list(client.gather(futures))
    finally:
        client.close()


def run_sweep(spec: SweepSpec, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True, connect_timeout_s: float = 10.0) -> SweepResult:
    """Evaluate every grid point: on ``workers`` local processes (default: all cores; 1 runs
    in this process) or, when ``scheduler`` (``tcp://HOST:PORT``) is given, on that Dask
    cluster (reached within ``connect_timeout_s`` s). The result does not depend on where
    the points ran."""
    tasks = [(p, spec.dt_s, spec.timing) for p in spec.points()]
    n_workers = worker_count(workers)
    start = time.perf_counter()
    with tqdm(total=len(tasks), desc=f"sweep {spec.mechanics}", unit="point",
              disable=not progress) as bar:
        if scheduler:
            results = _dask(tasks, scheduler, bar, connect_timeout_s)
        else:
            results = process_map(_evaluate, tasks, n_workers, on_result=lambda _: bar.update())
    values = {name: np.array([r[name] for r in results]).reshape(spec.shape)
              for name in MEASURES}
    return SweepResult(spec, values, time.perf_counter() - start)
