"""Everything ``skinhil reproduce`` computes, for one mechanics and readout, from documented
defaults.

Nothing here is tuned to a figure: the model is :class:`skinhil.SkinParams` with its defaults
at each amplitude (``SkinParams.at_amplitude``: only ``mechanics``, ``readout`` and the
amplitude change), the stimuli are the built-in paper stimuli, and
every analysis choice is the documented default of its module. The rules that pick what a
figure shows are fixed here, before any run: the sensors of M15, the paper's "sensor #5", the
operating SNR, and how far the damping grid is extended (:data:`EXTENSION_DECADES`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from skinhil.analysis.correlation import (
    sensors_of_mass,
    similarity_matrix,
    similarity_matrix_per_sensor,
)
from skinhil.analysis.decoding_snr import (
    PAPER_SNRS_DB,
    DecodingSetup,
    FeatureSet,
    decode_feature_sets,
)
from skinhil.analysis.information import InformationMeasures, measures_from_pcas, phase_pcas
from skinhil.analysis.pca import PhasePCA
from skinhil.analysis.phases import PhaseWindows
from skinhil.analysis.regime import Deformation, largest_relative_displacement, readout_gap, scaled
from skinhil.analysis.sweep import SweepResult, SweepSpec, log_values, run_sweep
from skinhil.decoding import CVResult, FeatureSpec
from skinhil.model.mechanics.readout import Readout
from skinhil.model.skin import Dynamics, SkinModel, SkinParams
from skinhil.model.stimuli import direction_conditions, figure_4a_stimulus, paper_stimuli
from skinhil.model.strain import StrainSummary, strain_summary
from skinhil.model.trials import simulate_trials
from skinhil.reproduce.claims import edge_of_optimum

logger = logging.getLogger(__name__)

FOCUS_MASS = 15
"""Figures 3F and 4D-G look at the sensors of M15 (the springs attached to it), where the
Figure 4 forces are applied."""
PAPER_SENSOR_RANK = 5
"""The paper decodes from "sensor #5" of the ten springs attached to M15. The paper numbers
masses, not springs, so which spring is its sensor #5 is not given; the rule, ours and fixed
in advance: the 5th of the ten in ascending spring number (the project's spring numbering,
docs/reproduce.md)."""
FIGURE_SNR_DB = 10.0
"""The paper's operating point (dB): the rasters (4C-D), PSP traces (4E) and the confusion
matrix (4F)."""
FOCUS_CONDITION = 2
"""Figure 4B-C show direction condition 2 (0°, 0.5 N: the strongest along +x)."""
FIGURE_TRIAL_S = 0.3
"""Length (s) of the trials shown in 4B-E: the 0.25 s indentation and 50 ms after it."""
EXTENSION_DECADES = 0.5
"""2B/2C: when the K-averaged nPC or SIR ratio peaks at an end of the damping grid, the grid is
extended past that end by this many decades (at the grid's own log spacing) ..."""
MAX_EXTENSIONS = 1
"""... at most this many times per end (``ReproduceConfig.extensions``; half a decade: the
geometric mechanics' cost per point grows with the damping, ~10 s a point at 1.6 N·s/m): an
optimum still at the edge then is reported as none within the extended grid."""
VALID_RATIO = 0.1
"""The regime: the small-displacement model counts as valid while every spring's relative
displacement |q_j − q_i| / L0 stays below this."""
AMPLITUDES: tuple[str, ...] = ("paper", "small")
"""The amplitude, the design's third factor, in the design's order
(:data:`skinhil.model.skin.AMPLITUDES`): "paper", the paper's regime (M, K and C of the
default skin x0.01: the paper's 0.5 N at 150-400 % strain); "small", the default skin, the
same modes, damping ratios and linear spring forces at 1/100 of the strain, where the
geometric dynamics and the length readout reduce to their small-displacement limits."""
TENSION_N: tuple[float, ...] = (0.0, 0.005, 0.0158, 0.05, 0.158, 0.5)
"""Baseline tensions (N) of the tension sweep: none, then log-spaced 5 mN..0.5 N, whose
transverse stiffness T/L on the 1 mm mesh (5..500 N/m) spans the stiffness sweep's range."""


@dataclass(frozen=True)
class ReproduceConfig:
    """Sizes of one run: K x C sweep grids (n_stiffness, n_damping) per mechanics, points
    per axis of the tension sweeps per mechanics, decoding setup (trials, folds, repeats;
    the rasters of 4D-E are the decoding's own trials), SNRs, response step ``dt_s`` (s),
    and where to run the sweeps.

    Defaults (the 2 x 2 x 2 design runs eight times what one mechanics and readout did, on
    a 2-core machine): 11 x 11 grids (odd, so the default K and C lie on the grid; 2A's
    extremes exactly 3 values), 5 values per tension slice (the default in the middle), 50
    trials per condition and 5 repeats of 5-fold CV (at 10 dB the split standard error is
    about a tenth of the finite trials' error, which more repeats cannot reduce; REPORT.md
    prints both). Larger grids and more repeats are options (``--grid``, ``--repeats``)."""

    sweep_linear: tuple[int, int] = (11, 11)
    sweep_geometric: tuple[int, int] = (11, 11)
    tension_linear: int = 5
    tension_geometric: int = 5
    decoding: DecodingSetup = field(default_factory=lambda: DecodingSetup(repeats=5))
    snrs_db: tuple[float, ...] = PAPER_SNRS_DB
    dt_s: float = 1e-4
    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True
    extensions: int = MAX_EXTENSIONS
    """How many times the damping grid may be extended per end for 2B/2C (--quick: 0)."""
    amplitudes: tuple[str, ...] = AMPLITUDES
    """Amplitude levels of the design (:data:`AMPLITUDES`); the tension sweeps run at the
    first only."""

    @classmethod
    def quick(cls, **kwargs: object) -> ReproduceConfig:
        """Small grids, few repeats and the paper's amplitude only (a 2 x 2 design): every
        figure but the other amplitude's 4E, for tests (time: docs/reproduce.md)."""
        base = cls(sweep_linear=(5, 5), sweep_geometric=(3, 3), tension_linear=3,
                   tension_geometric=1, decoding=DecodingSetup(reps=10, repeats=2),
                   extensions=0, amplitudes=("paper",))
        return replace(base, **kwargs)  # type: ignore[arg-type]


@dataclass
class MechanicsResults:
    """All numbers of one mechanics (arrays for the figures, scalars for the report).

    Figure 4 arrays, over :data:`FIGURE_TRIAL_S` at ``dt_s``: ``focus_forces`` (9 conditions,
    n_steps, 10) N at M15's sensors; ``condition_forces`` (n_steps, 338) N of
    :data:`FOCUS_CONDITION`; ``population_raster`` (n_steps, 338) one trial of it;
    ``sensor_trials`` (9, reps, n_steps, 10) the decoding's trials at the figure SNR, M15's
    sensors only.
    """

    mechanics: str
    readout: str
    amplitude: str
    params: SkinParams
    responses: np.ndarray
    pca_ind: PhasePCA
    pca_post: PhasePCA
    measures: InformationMeasures
    """1E-F's measures on stimulus 1 alone (the paper's Figure 1); ``pca_*`` are its."""
    stacked_pcas: tuple[PhasePCA, PhasePCA]
    stacked: InformationMeasures
    """The same for the five inputs stacked (an extra)."""
    focus_sensors: np.ndarray
    similarity: np.ndarray
    """3F's index, the per-sensor mean (as the paper); ``similarity_pooled`` the extra."""
    similarity_pooled: np.ndarray
    sweep: SweepResult
    """The K x C sweep with its damping grid extended for 2B/2C (:func:`extended_sweep`)."""
    sweep_base: SweepResult
    """The same sweep on the first grid only (a decade either side of the defaults): 2A's."""
    tension_k: SweepResult
    tension_c: SweepResult
    snrs_db: tuple[float, ...]
    feature_spec: FeatureSpec
    feature_sets: list[FeatureSet]
    decoding: dict[str, list[CVResult]]
    focus_forces: np.ndarray
    condition_forces: np.ndarray
    population_raster: np.ndarray
    sensor_trials: np.ndarray
    strain: dict[str, StrainSummary] = field(default_factory=dict)
    """Strain of the runs behind each analysis: "stimulus 1", "inputs" (the five),
    "conditions" (Figure 4's nine), "fig4A" (:func:`figure_4a_stimulus`)."""
    fig4a_sensor_n: float = math.nan
    """Largest tension (N) of the paper's sensor under the Figure 4A stimulus."""
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """Mechanics, readout and amplitude, as the report and the figures name the run."""
        return f"{self.mechanics}/{self.readout}/{self.amplitude}"

    @property
    def paper_sensor_spikes(self) -> np.ndarray:
        """Mean spikes per trial of the paper's sensor in each of the 9 conditions at
        :data:`FIGURE_SNR_DB` (the decoding's trials, over :data:`FIGURE_TRIAL_S`)."""
        column = int(np.flatnonzero(self.focus_sensors == self.paper_sensor)[0])
        return np.asarray(self.sensor_trials[..., column].sum(axis=2).mean(axis=1))

    @property
    def paper_sensor(self) -> int:
        """The sensor shown as the paper's "sensor #5" (see :data:`PAPER_SENSOR_RANK`)."""
        return int(self.focus_sensors[PAPER_SENSOR_RANK - 1])

    @property
    def paper_set(self) -> str:
        """Name of the feature set of the paper's sensor."""
        return sensor_set_name(self.paper_sensor)

    @property
    def paper_label(self) -> str:
        """The paper's set as figures and the report label it."""
        return f"{self.paper_set} (#{PAPER_SENSOR_RANK})"

    @property
    def figure_index(self) -> int:
        """Index into ``snrs_db`` (and each decoding list) of :data:`FIGURE_SNR_DB`."""
        return figure_snr_index(self.snrs_db)

    def at_figure_snr(self) -> dict[str, CVResult]:
        """Every feature set's result at :data:`FIGURE_SNR_DB`."""
        return {name: res[self.figure_index] for name, res in self.decoding.items()}


def sensor_set_name(sensor: int) -> str:
    """Feature set name of one sensor."""
    return f"sensor {sensor}"


TEN_SET = f"M{FOCUS_MASS}'s 10 sensors"
ALL_SET = "all 338 sensors"


def feature_sets(focus: np.ndarray) -> list[FeatureSet]:
    """Each sensor of M15 alone, the ten together, all 338 (Figure 4G's feature sets)."""
    sets = [FeatureSet(sensor_set_name(int(s)), (int(s),)) for s in focus]
    return sets + [FeatureSet(TEN_SET, tuple(int(s) for s in focus)), FeatureSet(ALL_SET)]


def figure_snr_index(snrs_db: tuple[float, ...]) -> int:
    """Index of the SNR nearest :data:`FIGURE_SNR_DB`."""
    return int(np.argmin([abs(s - FIGURE_SNR_DB) if math.isfinite(s) else math.inf
                          for s in snrs_db]))


def sweep_grid(n_k: int, n_c: int, base: SkinParams) -> SweepSpec:
    """The K x C grid a decade either side of ``base``'s stiffness and damping."""
    return SweepSpec.log_grid(n_k, n_c, mechanics=base.mechanics if base.mechanics != "auto"
                              else base.dynamics, base=base)


def _tension_sweeps(mechanics: Dynamics, readout: Readout, n: int, config: ReproduceConfig
                    ) -> tuple[SweepResult, SweepResult]:
    """Tension x K at the first amplitude's C, and tension x C at its K."""
    base = SkinParams.at_amplitude(config.amplitudes[0], readout=readout)
    full = SweepSpec.log_grid(n, n, mechanics=mechanics, base=base)
    specs = (SweepSpec(log_values(full.stiffness_n_per_m[0], full.stiffness_n_per_m[-1], n),
                       (base.damping_n_s_per_m,), TENSION_N, mechanics, base=base),
             SweepSpec((base.stiffness_n_per_m,),
                       log_values(full.damping_n_s_per_m[0], full.damping_n_s_per_m[-1], n),
                       TENSION_N, mechanics, base=base))
    k_sweep, c_sweep = (run_sweep(s, workers=config.workers, scheduler=config.scheduler,
                                  progress=config.progress) for s in specs)
    return k_sweep, c_sweep


def _run(spec: SweepSpec, config: ReproduceConfig) -> SweepResult:
    return run_sweep(spec, workers=config.workers, scheduler=config.scheduler,
                     progress=config.progress)


def extended_sweep(first: SweepResult, config: ReproduceConfig) -> SweepResult:
    """``first`` with its damping grid extended, :data:`EXTENSION_DECADES` at a time (at most
    ``config.extensions`` times per end), past every end at which the K-averaged nPC or SIR
    ratio peaks (:func:`skinhil.reproduce.claims.edge_of_optimum`), at the grid's log spacing
    or, if that is coarser, at :data:`EXTENSION_DECADES`."""
    result = first
    done = {"low": 0, "high": 0}
    while True:
        found = {edge_of_optimum(result.at(name)) for name in ("npc_ratio", "sir_ratio")}
        edges = {e for e in found if e is not None and done[e] < config.extensions}
        if not edges:
            return result
        for edge in sorted(edges):
            c = result.spec.damping_n_s_per_m
            step = min(c[1] / c[0] if len(c) > 1 else math.inf, 10 ** EXTENSION_DECADES)
            n_new = max(1, round(EXTENSION_DECADES / math.log10(step)))
            new = tuple(float(c[0] / step ** k) for k in range(n_new, 0, -1)) if edge == "low" \
                else tuple(float(c[-1] * step ** k) for k in range(1, n_new + 1))
            more = _run(replace(result.spec, damping_n_s_per_m=new), config)
            parts = [more, result] if edge == "low" else [result, more]
            spec = replace(result.spec, damping_n_s_per_m=parts[0].spec.damping_n_s_per_m
                           + parts[1].spec.damping_n_s_per_m)
            values = {k: np.concatenate([p.values[k] for p in parts], axis=2)
                      for k in result.values}
            result = SweepResult(spec, values, result.seconds + more.seconds)
            done[edge] += 1
            logger.info("damping grid extended at its %s end to %s", edge,
                        spec.damping_n_s_per_m)


@dataclass(frozen=True)
class Regime:
    """How large the deformation is in the paper regime, per mechanics: the largest
    relative displacement per stimulus, and for the linear dynamics the force below which
    the small-displacement model holds (:data:`VALID_RATIO`) and how far the readouts part
    there and at the paper's force."""

    per_stimulus: dict[str, dict[str, Deformation]]
    """mechanics → stimulus name → its largest relative displacement."""
    valid_force_n: float
    """Force of the 0°, 0.5 N condition scaled down until the linear mesh's largest relative
    displacement is :data:`VALID_RATIO` (N)."""
    gap_at_valid: float
    gap_at_paper: float
    """max |length − axial| / max |length| of the linear dynamics at that force and at 0.5 N."""


def compute_regime(dt_s: float) -> Regime:
    """The regime of the paper amplitude: every paper stimulus (over the 0.5 s of the
    analyses) and every Figure 4 condition (over :data:`FIGURE_TRIAL_S`), both mechanics."""
    per: dict[str, dict[str, Deformation]] = {}
    for mechanics in ("linear", "geometric"):
        model = SkinModel(SkinParams.at_amplitude("paper", mechanics=mechanics))
        runs = [(s, 0.5) for s in paper_stimuli()]
        runs += [(s, FIGURE_TRIAL_S) for s in [*direction_conditions(), figure_4a_stimulus()]]
        per[mechanics] = {s.name: largest_relative_displacement(model, s, d, dt_s)
                          for s, d in runs}
    linear = SkinModel(SkinParams.at_amplitude("paper", mechanics="linear"))
    paper = direction_conditions()[FOCUS_CONDITION]
    factor = VALID_RATIO / per["linear"][paper.name].ratio  # linear in the force
    force = float(np.linalg.norm(next(iter(paper.forces.values()))))
    return Regime(per, factor * force,
                  readout_gap(linear, scaled(paper, factor), FIGURE_TRIAL_S, dt_s),
                  readout_gap(linear, paper, FIGURE_TRIAL_S, dt_s))


def compute_mechanics(mechanics: Dynamics, readout: Readout, config: ReproduceConfig,
                      amplitude: str = "paper") -> MechanicsResults:
    """Run every analysis for one mechanics, readout and amplitude (:data:`AMPLITUDES`) with
    default parameters otherwise."""
    base = SkinParams.at_amplitude(amplitude, mechanics=mechanics, readout=readout)
    model = SkinModel(base)
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    stimuli = paper_stimuli()
    windows = PhaseWindows.of(stimuli)
    responses = model.simulate_many(stimuli, windows.duration_s, config.dt_s)
    pca_ind, pca_post = phase_pcas(responses[:1], config.dt_s, windows)
    stacked = phase_pcas(responses, config.dt_s, windows)
    focus = sensors_of_mass(model.springs, FOCUS_MASS)
    similarity = similarity_matrix_per_sensor(responses[:, :, focus])
    pooled = similarity_matrix(responses[:, :, focus])
    strain = {"stimulus 1": strain_summary(responses[:1], base),
              "inputs": strain_summary(responses, base)}
    seconds["information"] = time.perf_counter() - t0

    grid = config.sweep_linear if mechanics == "linear" else config.sweep_geometric
    sweep_base = _run(sweep_grid(*grid, base), config)
    sweep = extended_sweep(sweep_base, config)
    seconds["sweep"] = sweep.seconds
    if amplitude == config.amplitudes[0]:
        n_t = config.tension_linear if mechanics == "linear" else config.tension_geometric
        tension_k, tension_c = _tension_sweeps(mechanics, readout, n_t, config)
        seconds["tension sweeps"] = tension_k.seconds + tension_c.seconds
    else:  # the tension axis is shown at the first amplitude only
        tension_k = tension_c = SweepResult(replace(sweep_base.spec, tension_n=(0.0,)), {}, 0.0)

    t0 = time.perf_counter()
    d = config.decoding
    sets = feature_sets(focus)
    decoding = decode_feature_sets(sets, config.snrs_db, d, model, workers=config.workers,
                                   progress=config.progress)
    seconds["decoding"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    conditions = direction_conditions()
    forces = model.simulate_many(conditions, FIGURE_TRIAL_S, config.dt_s)
    strain["conditions"] = strain_summary(forces, base)
    fig4a = model.simulate(figure_4a_stimulus(), FIGURE_TRIAL_S, config.dt_s)
    strain["fig4A"] = strain_summary(fig4a, base)
    # the decoding's own trials at the figure SNR (same seed, reps and step), run longer
    i_fig = figure_snr_index(config.snrs_db)
    sensor_trials = simulate_trials(conditions, d.reps, duration_s=FIGURE_TRIAL_S,
                                    dt_s=config.dt_s, snr_db=config.snrs_db[i_fig],
                                    seed=d.seed + i_fig, model=model,
                                    channels=[int(s) for s in focus])
    population = simulate_trials([conditions[FOCUS_CONDITION]], 1, duration_s=FIGURE_TRIAL_S,
                                 dt_s=config.dt_s, snr_db=config.snrs_db[i_fig],
                                 seed=d.seed + len(config.snrs_db), model=model)[0, 0]
    seconds["rasters"] = time.perf_counter() - t0
    logger.info("%s mechanics, %s readout, %s amplitude done: %s", mechanics, readout,
                amplitude, seconds)
    paper_sensor = int(focus[PAPER_SENSOR_RANK - 1])
    return MechanicsResults(
        mechanics, readout, amplitude, base, responses, pca_ind, pca_post,
        measures_from_pcas(pca_ind, pca_post), stacked, measures_from_pcas(*stacked), focus,
        similarity, pooled, sweep, sweep_base, tension_k, tension_c, tuple(config.snrs_db),
        d.spec, sets, decoding, forces[:, :, focus], forces[FOCUS_CONDITION], population,
        sensor_trials, strain, float(fig4a[:, paper_sensor].max()), seconds)


SUPPLEMENTARY_FACTORS: tuple[float, ...] = (0.1, 1.0, 10.0)
"""Supplementary Figure 1: stiffness and damping at these multiples of the paper regime's
(3 x 3)."""


@dataclass(frozen=True)
class SupplementaryPoint:
    """One panel pair of Supplementary Figure 1: stiffness (N/m), damping (N·s/m), M15's
    sensors' forces (n_steps, 10) N under stimulus 1, and its two phases' PCA curves."""

    stiffness_n_per_m: float
    damping_n_s_per_m: float
    forces: np.ndarray
    curve_ind: np.ndarray
    curve_post: np.ndarray


def compute_supplementary(dt_s: float) -> list[SupplementaryPoint]:
    """Supplementary Figure 1 on the paper's linear model (linear dynamics, axial readout):
    the sensor responses to stimulus 1 and the variance-explained curves of each phase, per
    K x C of :data:`SUPPLEMENTARY_FACTORS` (K-major)."""
    base = SkinParams.at_amplitude("paper", mechanics="linear", readout="axial")
    stimulus = paper_stimuli()[:1]
    windows = PhaseWindows.of(stimulus)
    out = []
    for fk in SUPPLEMENTARY_FACTORS:
        for fc in SUPPLEMENTARY_FACTORS:
            params = replace(base, stiffness_n_per_m=base.stiffness_n_per_m * fk,
                             damping_n_s_per_m=base.damping_n_s_per_m * fc)
            model = SkinModel(params)
            r = model.simulate_many(stimulus, windows.duration_s, dt_s)
            ind, post = phase_pcas(r, dt_s, windows)
            focus = sensors_of_mass(model.springs, FOCUS_MASS)
            out.append(SupplementaryPoint(params.stiffness_n_per_m, params.damping_n_s_per_m,
                                          r[0][:, focus], ind.curve, post.curve))
    return out
