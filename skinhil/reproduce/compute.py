"""Everything ``skinhil reproduce`` computes, for one mechanics, from documented defaults.

Nothing here is tuned to a figure: the model is :class:`skinhil.SkinParams` with its defaults
(only ``mechanics`` changes), the stimuli are the built-in paper stimuli, and every analysis
choice is the documented default of its module.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from skinhil.analysis.correlation import sensors_of_mass, similarity_matrix
from skinhil.analysis.decoding_snr import (
    PAPER_SNRS_DB,
    DecodingSetup,
    accuracy_vs_snr,
)
from skinhil.analysis.information import InformationMeasures, measures_from_pcas, phase_pcas
from skinhil.analysis.pca import PhasePCA
from skinhil.analysis.phases import PhaseWindows
from skinhil.analysis.sweep import SweepResult, SweepSpec, run_sweep
from skinhil.decoding import CVResult
from skinhil.skin import Mechanics, SkinModel, SkinParams
from skinhil.stimuli import direction_conditions, paper_stimuli
from skinhil.trials import simulate_trials

logger = logging.getLogger(__name__)

FOCUS_MASS = 15
"""Figure 3F and 4D look at the sensors of M15, where the stimuli are applied."""
FOCUS_CONDITION = 2
"""Figure 4B-E show direction condition 2 (0°, 0.5 N: the strongest along +x)."""
FIGURE_SNR_DB = 20.0
"""SNR (dB) of the rasters (4C-D) and the confusion matrix (4F): the middle of 4G's range."""


@dataclass(frozen=True)
class ReproduceConfig:
    """Sizes of one run: sweep grids (n_stiffness, n_damping) per mechanics, decoding setup,
    SNRs, raster repetitions, response step ``dt_s`` (s), and where to run the sweeps."""

    sweep_linear: tuple[int, int] = (20, 20)
    sweep_geometric: tuple[int, int] = (20, 20)
    decoding: DecodingSetup = field(default_factory=DecodingSetup)
    snrs_db: tuple[float, ...] = PAPER_SNRS_DB
    raster_reps: int = 50
    dt_s: float = 1e-4
    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True

    @classmethod
    def quick(cls, **kwargs: object) -> ReproduceConfig:
        """Small grids and few repeats: every figure in well under a minute."""
        base = cls(sweep_linear=(5, 5), sweep_geometric=(2, 2),
                   decoding=DecodingSetup(reps=8, repeats=2), raster_reps=10)
        return replace(base, **kwargs)  # type: ignore[arg-type]


@dataclass
class MechanicsResults:
    """All numbers of one mechanics (arrays for the figures, scalars for the report)."""

    mechanics: str
    responses: np.ndarray
    pca_ind: PhasePCA
    pca_post: PhasePCA
    measures: InformationMeasures
    focus_sensors: np.ndarray
    similarity: np.ndarray
    sweep: SweepResult
    snrs_db: tuple[float, ...]
    decoding: list[CVResult]
    direction_forces: np.ndarray
    raster_sensor: int
    rasters: np.ndarray
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def confusion_index(self) -> int:
        """Index into ``decoding`` of the SNR the confusion matrix is shown at."""
        return int(np.argmin([abs(s - FIGURE_SNR_DB) if math.isfinite(s) else math.inf
                              for s in self.snrs_db]))


def compute_mechanics(mechanics: Mechanics, config: ReproduceConfig) -> MechanicsResults:
    """Run every analysis for one mechanics with default parameters."""
    model = SkinModel(SkinParams(mechanics=mechanics))
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    stimuli = paper_stimuli()
    windows = PhaseWindows.of(stimuli)
    responses = model.simulate_many(stimuli, windows.duration_s, config.dt_s)
    pca_ind, pca_post = phase_pcas(responses, config.dt_s, windows)
    focus = sensors_of_mass(model.springs, FOCUS_MASS)
    similarity = similarity_matrix(responses[:, :, focus])
    seconds["information"] = time.perf_counter() - t0

    grid = config.sweep_linear if mechanics == "linear" else config.sweep_geometric
    sweep = run_sweep(SweepSpec.log_grid(*grid, mechanics=mechanics), workers=config.workers,
                      scheduler=config.scheduler, progress=config.progress)
    seconds["sweep"] = sweep.seconds

    t0 = time.perf_counter()
    d = config.decoding
    # worker processes pay off only for many folds (starting them costs seconds)
    n_jobs = 1 if d.folds * d.repeats <= 50 else (config.workers or -1)
    decoding = accuracy_vs_snr(config.snrs_db, config.decoding, model, n_jobs=n_jobs,
                               progress=config.progress)
    seconds["decoding"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    conditions = direction_conditions()
    direction_forces = model.simulate_many(conditions, windows.duration_s, config.dt_s)
    focus_forces = direction_forces[FOCUS_CONDITION][:, focus]
    raster_sensor = int(focus[np.argmax(focus_forces.max(axis=0))])
    rasters = simulate_trials([conditions[FOCUS_CONDITION]], config.raster_reps,
                              duration_s=windows.duration_s, dt_s=config.dt_s,
                              snr_db=FIGURE_SNR_DB, seed=config.decoding.seed, model=model)[0]
    seconds["rasters"] = time.perf_counter() - t0
    logger.info("%s mechanics done: %s", mechanics, seconds)
    return MechanicsResults(mechanics, responses, pca_ind, pca_post,
                            measures_from_pcas(pca_ind, pca_post), focus, similarity, sweep,
                            tuple(config.snrs_db), decoding, direction_forces, raster_sensor,
                            rasters, seconds)
