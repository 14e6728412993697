"""REPORT.md and results.json of ``skinhil reproduce``: every number, every claim's verdict."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.analysis.decoding_snr import CHANCE, split_standard_error, trial_standard_error
from skinhil.analysis.pca import N_SIR_COMPONENTS
from skinhil.analysis.sweep import SweepResult
from skinhil.decoding import CVResult
from skinhil.model.skin import AMPLITUDES as SKIN_AMPLITUDES
from skinhil.model.skin import DEFAULT_AMPLITUDE, SkinModel
from skinhil.model.stimuli import paper_stimuli
from skinhil.model.strain import StrainSummary
from skinhil.output_files import write_text
from skinhil.reproduce import claims
from skinhil.reproduce.compute import (
    ALL_SET,
    EXTENSION_DECADES,
    FIGURE_SNR_DB,
    FIGURE_TRIAL_S,
    FOCUS_CONDITION,
    FOCUS_MASS,
    PAPER_SENSOR_RANK,
    TEN_SET,
    VALID_RATIO,
    MechanicsResults,
    Regime,
    ReproduceConfig,
    sensor_set_name,
)
from skinhil.reproduce.figures import FIGURES
from skinhil.reproduce.paper_search import search_lines

CLAIM_KEYS: tuple[str, ...] = ("1E-F", "2A", "2B", "2C", "3F", "4F", "4G")
"""The paper's claims checked, one REPORT.md row each per mechanics and readout."""
OTHER = {"linear": "geometric", "geometric": "linear", "length": "axial", "axial": "length"}
FACTOR_NAMES = ("dynamics", "readout", "amplitude")
Combo = tuple[str, str, str]
"""(mechanics, readout, amplitude) of one run."""


def verdicts(r: MechanicsResults) -> list[tuple[claims.Verdict, str]]:
    """Each claim's verdict for one mechanics (order :data:`CLAIM_KEYS`), with the figure
    file that shows it."""
    names = [s.name for s in paper_stimuli()]
    out = [
        (claims.information_phases(r.measures, r.stacked), "fig1E_variance_explained.png"),
        (claims.area_flat_except_extremes(r.sweep_base), "fig2ABC_sweeps.png"),
        (claims.npc_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.sir_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.inputs_2_3_most_similar(r.similarity, names, _rms_at_focus(r),
                                        r.similarity_pooled), "fig3F_similarity.png"),
        (claims.decoding_at_operating_point(r.snrs_db[r.figure_index],
                                            _headline(r.at_figure_snr(), r), r.paper_label,
                                            r.paper_sensor_spikes),
         "fig4F_confusion.png"),
        (claims.decoding_rises_with_snr(r.snrs_db, _headline(r.decoding, r), r.paper_label),
         "fig4G_accuracy_vs_snr.png"),
    ]
    return out


def _sweep_strain(sw: SweepResult) -> StrainSummary:
    """The strain of a sweep's runs: the largest of its points' and the median of theirs."""
    mx, md = sw.at("max_strain"), sw.at("median_strain")
    if not np.isfinite(mx).any():
        return StrainSummary(math.nan, math.nan)
    return StrainSummary(float(np.nanmax(mx)), float(np.nanmedian(md)))


def claim_strain(r: MechanicsResults, key: str) -> StrainSummary:
    """The strain of the runs behind claim ``key``'s verdict for run ``r``: stimulus 1 (1E-F),
    the sweep's points (2A: the first grid; 2B, 2C: as extended), the five inputs (3F), the
    nine conditions (4F, 4G)."""
    if key == "1E-F":
        return r.strain["stimulus 1"]
    if key == "2A":
        return _sweep_strain(r.sweep_base)
    if key in ("2B", "2C"):
        return _sweep_strain(r.sweep)
    if key == "3F":
        return r.strain["inputs"]
    return r.strain["conditions"]


def _pct(x: float) -> str:
    return "NaN" if math.isnan(x) else f"{x:.0%}" if x >= 0.1 else f"{x:.2%}"


def _strain_cell(st: StrainSummary) -> str:
    return f"{_pct(st.max)} / {_pct(st.median)}"


def _rms_at_focus(r: MechanicsResults) -> list[float]:
    """Each input's RMS force (N) at M15's sensors over the simulated response."""
    focus = r.responses[:, :, r.focus_sensors]
    return [float(np.sqrt(np.mean(f * f))) for f in focus]


def _headline(d: dict[str, Any], r: MechanicsResults) -> dict[str, Any]:
    """The three feature sets of Figure 4G by label, the paper's sensor first."""
    return {r.paper_label: d[r.paper_set], TEN_SET: d[TEN_SET], ALL_SET: d[ALL_SET]}


def _num(v: float) -> str:
    return "NaN" if isinstance(v, float) and math.isnan(v) else f"{v:.4g}"


def _snr(s: float) -> str:
    return f"{s:g}" if math.isfinite(s) else "inf"


def likely_cause(outcome: dict[Combo, bool], combo: Combo) -> str:
    """The cause of a claim not reproduced by run ``combo`` (mechanics, readout, amplitude),
    named from the run's design (``outcome`` maps each run's combo → reproduced): the factors
    whose swap alone, the others held fixed, reproduces it; else the smallest pair of swaps
    that does; else none. Rule fixed in advance; empty if reproduced or if no swapped run
    exists."""
    if outcome.get(combo, True):
        return ""
    levels = [sorted({c[i] for c in outcome}) for i in range(3)]

    def swapped(factors: tuple[int, ...]) -> list[Combo]:
        out: list[Combo] = [combo]
        for i in factors:
            out = [tuple(v if k == i else c[k] for k in range(3))  # type: ignore[misc]
                   for c in out for v in levels[i] if v != combo[i]]
        return out

    def describe(c: Combo) -> str:
        return f"{c[0]}/{c[1]}/{c[2]}"

    for size in (1, 2, 3):
        groups = [(f, [c for c in swapped(f) if outcome.get(c)])
                  for f in _factor_sets(size)]
        hits = [(f, cs) for f, cs in groups if cs]
        if hits:
            if size == 1 and len(hits) > 1:
                return ("either factor: " + "; ".join(
                    f"the {FACTOR_NAMES[f[0]]} ({', '.join(describe(c) for c in cs)} "
                    "reproduces it)" for f, cs in hits))
            f, cs = hits[0]
            names = " and ".join(FACTOR_NAMES[i] for i in f)
            prefix = "the " if size == 1 else "only together: the "
            return f"{prefix}{names}: {', '.join(describe(c) for c in cs)} reproduces it"
    if len(outcome) < 2:
        return ""
    return "none: no run of this design reproduces it"


def _factor_sets(size: int) -> list[tuple[int, ...]]:
    from itertools import combinations

    return list(combinations(range(3), size))


def _combo(r: MechanicsResults) -> Combo:
    return (r.mechanics, r.readout, r.amplitude)


def _outcomes(results: Sequence[MechanicsResults]) -> dict[str, dict[Combo, bool]]:
    """Claim key → (mechanics, readout, amplitude) → reproduced."""
    out: dict[str, dict[Combo, bool]] = {k: {} for k in CLAIM_KEYS}
    for r in results:
        for v, _ in verdicts(r):
            out[v.key][_combo(r)] = v.reproduced
    return out


def claim_counts(results: Sequence[MechanicsResults]) -> dict[str, int]:
    """Label (mechanics/readout/amplitude) → claims reproduced."""
    return {r.label: sum(v.reproduced for v, _ in verdicts(r)) for r in results}


def _claims_table(results: Sequence[MechanicsResults]) -> list[str]:
    lines = ["| panel | claim | mechanics | readout | amplitude | strain max / median | "
             "reproduced | evidence | what failed | likely cause (this run's design) | "
             "figure |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = {r.label: verdicts(r) for r in results}
    outcomes = _outcomes(results)
    for k, key in enumerate(CLAIM_KEYS):
        for r in results:
            v, fig = rows[r.label][k]
            cause = likely_cause(outcomes[key], _combo(r))
            lines.append(f"| {v.key} | {v.claim} | {r.mechanics} | {r.readout} | "
                         f"{r.amplitude} | {_strain_cell(claim_strain(r, key))} | "
                         f"{'yes' if v.reproduced else '**no**'} | {v.evidence} | "
                         f"{v.reason or '—'} | {cause or '—'} | [{fig}]({fig}) |")
    counts = ", ".join(f"{label} **{n} of {len(CLAIM_KEYS)}**"
                       for label, n in claim_counts(results).items())
    return lines + ["", f"Claims reproduced: {counts}.", ""]


def _where_lines(results: Sequence[MechanicsResults]) -> list[str]:
    """Per claim and amplitude: the runs that reproduce it, with their strain."""
    amps = list(dict.fromkeys(r.amplitude for r in results))
    lines = ["## Where each claim holds", "",
             "Per claim and amplitude, the mechanics/readout runs that reproduce it and the "
             "largest strain of the runs behind those verdicts (max / median, "
             "`skinhil/model/strain.py`):", "",
             "| claim | " + " | ".join(f"{a} amplitude" for a in amps) + " |",
             "|---" * (len(amps) + 1) + "|"]
    for k, key in enumerate(CLAIM_KEYS):
        cells = []
        for a in amps:
            held = [(r, claim_strain(r, key)) for r in results
                    if r.amplitude == a and verdicts(r)[k][0].reproduced]
            cells.append("; ".join(f"{r.mechanics}/{r.readout} ({_strain_cell(st)})"
                                   for r, st in held) or "none")
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return lines + [""]


def _regime_lines(regime: Regime) -> list[str]:
    names = list(next(iter(regime.per_stimulus.values())))
    mechs = list(regime.per_stimulus)
    lines = ["## Regime: how large the deformation is", "",
             "Largest relative displacement |q_j − q_i| / L0 of any spring (its ends' relative "
             "displacement over its rest length) in the paper regime (the paper amplitude), "
             "per stimulus "
             "(paper inputs over 0.5 s, Figure 4 conditions over "
             f"{FIGURE_TRIAL_S:g} s), per mechanics; the spring (0-based) and when:", "",
             "| stimulus | " + " | ".join(mechs) + " |", "|---" * (len(mechs) + 1) + "|"]
    for name in names:
        cells = [f"{d.ratio:.2f} (spring {d.spring}, {d.t_s * 1e3:.1f} ms)"
                 for d in (regime.per_stimulus[m][name] for m in mechs)]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", f"The small-displacement model (the linear stiffness matrix and its axial "
              f"readout, first order in |q_j − q_i| / L0) is taken as valid while the ratio "
              f"stays below {VALID_RATIO:g}: on the linear mesh that holds for the 0°/0.5 N "
              f"condition scaled down to {regime.valid_force_n * 1e3:.3g} mN; there the two "
              f"readouts of the linear dynamics differ by {regime.gap_at_valid:.1%} of the "
              f"largest force, at 0.5 N by {regime.gap_at_paper:.0%}. Every paper stimulus "
              "lies far beyond it, in both mechanics. The last row is the paper's Figure 4A "
              "stimulus (Fx = Fy = 0.5 N on M15), which is not one of the nine decoded "
              "conditions.", ""]
    return lines


def _decoding_tables(r: MechanicsResults, config: ReproduceConfig) -> list[str]:
    snrs = r.snrs_db
    head = "| feature set | " + " | ".join(f"{_snr(s)} dB" for s in snrs) + " |"
    rule = "|---" * (len(snrs) + 1) + "|"
    lines = [f"### Decoding the 9 direction conditions (Fig 4D-G), {r.mechanics}", "",
             "Accuracy (mean over the test folds) per feature set and SNR:", "", head, rule]
    for label, res in _headline(r.decoding, r).items():
        lines.append(f"| {label} | " + " | ".join(f"{cv.accuracy:.3f}" for cv in res) + " |")
    model = SkinModel(r.params)
    lines += ["", f"Each spring attached to M{FOCUS_MASS} alone (ascending spring number; "
              f"rank {PAPER_SENSOR_RANK} is the one shown as the paper's sensor #5); "
              f"band: well above chance and well below 100 % at {FIGURE_SNR_DB:g} dB "
              f"({claims.WELL_ABOVE_CHANCE * CHANCE:.2f}..{claims.WELL_BELOW_FULL:.2f}):", "",
              "| rank | sensor | spring | " + " | ".join(f"{_snr(s)} dB" for s in snrs)
              + f" | in the band at {FIGURE_SNR_DB:g} dB |",
              "|---|---|---" + "|---" * (len(snrs) + 1) + "|"]
    in_band = 0
    i_fig = r.figure_index
    for rank, s in enumerate(r.focus_sensors, start=1):
        res = r.decoding[sensor_set_name(int(s))]
        a, b = model.springs[int(s)] + 1
        ok = claims.WELL_ABOVE_CHANCE * CHANCE <= res[i_fig].accuracy <= claims.WELL_BELOW_FULL
        in_band += ok
        mark = "**5**" if rank == PAPER_SENSOR_RANK else str(rank)
        lines.append(f"| {mark} | {int(s)} | M{a}–M{b} | "
                     + " | ".join(f"{cv.accuracy:.3f}" for cv in res)
                     + f" | {'yes' if ok else 'no'} |")
    singles = np.array([r.decoding[sensor_set_name(int(s))][i_fig].accuracy
                        for s in r.focus_sensors])
    lines += ["", f"At {FIGURE_SNR_DB:g} dB, {in_band} of {len(r.focus_sensors)} single "
              f"sensors lie in the band; single-sensor accuracy {singles.min():.3f}.."
              f"{singles.max():.3f} (median {np.median(singles):.3f}); chance {CHANCE:.3f}.",
              ""]
    cv = r.decoding[r.paper_set][i_fig]
    lines += [f"Statistical error at {FIGURE_SNR_DB:g} dB ({config.decoding.repeats} repeats "
              f"of {cv.folds}-fold CV): from the finite trials ±"
              f"{trial_standard_error(cv):.3f} (binomial, sensor {r.paper_sensor}), from the "
              f"fold splits ±{split_standard_error(cv):.3f}; for all 338 sensors ±"
              f"{trial_standard_error(r.decoding[ALL_SET][i_fig]):.3f} and ±"
              f"{split_standard_error(r.decoding[ALL_SET][i_fig]):.3f}.", "",
              f"Confusion matrix of sensor {r.paper_sensor} at {FIGURE_SNR_DB:g} dB (rows: "
              "true condition, columns: predicted; fraction of trials):", "",
              "| | " + " | ".join(str(c) for c in cv.classes) + " |",
              "|---" * (len(cv.classes) + 1) + "|"]
    for i, c in enumerate(cv.classes):
        lines.append(f"| {c} | " + " | ".join(f"{v:.2f}" for v in cv.confusion_fraction[i])
                     + " |")
    counts = r.paper_sensor_spikes
    lines += ["", f"Rasters (Fig 4D-E): the decoding's own {r.sensor_trials.shape[1]} trials per "
              f"condition at {FIGURE_SNR_DB:g} dB, run for {FIGURE_TRIAL_S:g} s. Spikes per "
              f"trial of sensor {r.paper_sensor} per condition 0..8: "
              + ", ".join(f"{c:.1f}" for c in counts) + ". Fig 4C is one trial of condition "
              f"{FOCUS_CONDITION} ({int(r.population_raster.sum())} spikes over all "
              f"sensors). The paper's Figure 4A stimulus (Fx = Fy = 0.5 N on M15, not decoded): "
              f"sensor {r.paper_sensor}'s largest tension {r.fig4a_sensor_n * 1e3:.3g} mN; "
              f"{r.strain['fig4A'].text()}.", ""]
    return lines


def _sweep_lines(sw: SweepResult, first: SweepResult, extensions: int) -> list[str]:
    c0, c1 = first.spec.damping_n_s_per_m[0], first.spec.damping_n_s_per_m[-1]
    extended = ("" if sw.spec.damping_n_s_per_m == first.spec.damping_n_s_per_m else
                f" The first grid's damping ran {c0:g}..{c1:g} N·s/m; it was extended (by "
                f"{EXTENSION_DECADES:g} decade at a time, at most {extensions} times per "
                "end) where the K-averaged nPC or SIR ratio peaked at an end.")
    strain = _sweep_strain(sw)
    lines = [f"Stiffness K {sw.spec.stiffness_n_per_m[0]:g}..{sw.spec.stiffness_n_per_m[-1]:g}"
             f" N/m x damping C {sw.spec.damping_n_s_per_m[0]:g}.."
             f"{sw.spec.damping_n_s_per_m[-1]:g} N·s/m (log-spaced, {sw.spec.shape[1]} x "
             f"{sw.spec.shape[2]}), {sw.seconds:.1f} s.{extended} Strain over the grid: "
             f"max {_pct(strain.max)}, median of the points' medians {_pct(strain.median)}.",
             "",
             "| measure | min | median | max | NaN points |", "|---|---|---|---|---|"]
    for name in ("area", "npc_ratio", "sir_ratio", "sir_literal_ratio", "npc99_ind",
                 "npc99_post", "sir_ind", "sir_post", "max_strain", "median_strain"):
        v = sw.at(name)
        finite = v[np.isfinite(v)]
        stats = [_num(float(f(finite))) if finite.size else "NaN"
                 for f in (np.min, np.median, np.max)]
        lines.append(f"| {name} | {' | '.join(stats)} | {int(np.isnan(v).sum())} |")
    lines += ["", "Profile along damping, averaged over K (2B/2C's rule):", ""]
    for name in ("npc_ratio", "sir_ratio", "sir_literal_ratio"):
        prof = claims.damping_profile(sw.at(name))
        lines.append(f"- {name}: " + ", ".join(
            f"{c:.3g}: {_num(float(p))}" for c, p in zip(sw.spec.damping_n_s_per_m, prof,
                                                         strict=True)))
    lit = claims.sir_ratio_region(_as_sir(sw, "sir_literal_ratio"))
    lines += ["", f"2C with the literal eq. 10 SIR in place of the project's reading: "
              f"{'holds' if lit.reproduced else 'does not hold'} ({lit.evidence}"
              f"{'; ' + lit.reason if lit.reason else ''}).", ""]
    lines += ["", "Mean per tercile block (rows: K low, mid, high; columns: C low, mid, high):",
              ""]
    for name in ("area", "npc_ratio", "sir_ratio"):
        m = claims.tercile_means(sw.at(name))
        rows = ["/".join(_num(float(x)) for x in row) for row in m]
        lines.append(f"- {name}: K low {rows[0]}; K mid {rows[1]}; K high {rows[2]}")
    return lines + [""]


def _as_sir(sw: SweepResult, name: str) -> SweepResult:
    """``sw`` with measure ``name`` in the place of the SIR ratio (2C's rule on it)."""
    return SweepResult(sw.spec, {**sw.values, "sir_ratio": sw.values[name]}, sw.seconds)


def _tension_lines(r: MechanicsResults) -> list[str]:
    if not r.tension_k.values:
        return []
    lines = ["### Baseline tension (third sweep axis)", "",
             "Range of each measure over the tensions "
             f"({', '.join(f'{t:g}' for t in r.tension_k.spec.tension_n)} N), per slice:", "",
             "| measure | tension x K (C default) | tension x C (K default) | "
             "SIR ratio > 1 |", "|---|---|---|---|"]
    for name in ("area", "npc_ratio", "sir_ratio"):
        a, b = r.tension_k.values[name], r.tension_c.values[name]
        frac = ""
        if name == "sir_ratio":
            both = np.concatenate([a.ravel(), b.ravel()])
            frac = f"{np.mean(both > 1):.0%} of {both.size} points"
        lines.append(f"| {name} | {_num(float(np.nanmin(a)))}..{_num(float(np.nanmax(a)))} | "
                     f"{_num(float(np.nanmin(b)))}..{_num(float(np.nanmax(b)))} | {frac} |")
    return lines + ["", f"Compute time: {r.tension_k.seconds + r.tension_c.seconds:.1f} s.", ""]


def _mechanics_section(r: MechanicsResults, config: ReproduceConfig) -> list[str]:
    m, st = r.measures, r.stacked
    names = [s.name for s in paper_stimuli()]
    p = r.params
    lines = [f"## {r.mechanics} mechanics, {r.readout} readout, {r.amplitude} amplitude", "",
             f"M {p.mass_kg:g} kg, K {p.stiffness_n_per_m:g} N/m, C {p.damping_n_s_per_m:g} "
             f"N·s/m. Strain (max / median of the springs' peaks): stimulus 1 "
             f"{_strain_cell(r.strain['stimulus 1'])}, the five inputs "
             f"{_strain_cell(r.strain['inputs'])}, the nine conditions "
             f"{_strain_cell(r.strain['conditions'])}.", "",
             "### Information content at the default parameters (Fig 1E-F)", "",
             "Stimulus 1 (the paper's Figure 1, judged) and the five inputs stacked (an extra):",
             "", "| measure | indentation | post-indentation | ratio ind/post |",
             "|---|---|---|---|",
             f"| nPC for 99% variance, stimulus 1 | {_num(m.npc99_ind)} | {_num(m.npc99_post)} | "
             f"{_num(m.npc_ratio)} |",
             f"| signal-information ratio (PC1-{N_SIR_COMPONENTS}), stimulus 1 | "
             f"{_num(m.sir_ind)} | {_num(m.sir_post)} | {_num(m.sir_ratio)} |",
             f"| literal eq. 10 SIR, stimulus 1 | {_num(m.sir_literal_ind)} | "
             f"{_num(m.sir_literal_post)} | {_num(m.sir_literal_ratio)} |",
             f"| nPC for 99% variance, 5 stacked | {_num(st.npc99_ind)} | "
             f"{_num(st.npc99_post)} | {_num(st.npc_ratio)} |",
             f"| signal-information ratio, 5 stacked | {_num(st.sir_ind)} | "
             f"{_num(st.sir_post)} | {_num(st.sir_ratio)} |",
             f"| literal eq. 10 SIR, 5 stacked | {_num(st.sir_literal_ind)} | "
             f"{_num(st.sir_literal_post)} | {_num(st.sir_literal_ratio)} |", "",
             f"Area between the variance-explained curves (ind − post, in PCs, the paper's "
             f"sign: negative when the indentation needs more components): stimulus 1 "
             f"**{_num(m.area)}**, stacked {_num(st.area)}. Variance explained by PC1-3, "
             f"stimulus 1: indentation {_num(float(r.pca_ind.curve[2]))}, post-indentation "
             f"{_num(float(r.pca_post.curve[2]))}.", "",
             "### Sweep of stiffness x damping (Fig 2A-C)", ""]
    lines += _sweep_lines(r.sweep, r.sweep_base, config.extensions)
    lines += _tension_lines(r)
    lines += [f"### Correlation index between the inputs at M{FOCUS_MASS}'s sensors (Fig 3F)",
              "", f"Sensors (springs attached to M{FOCUS_MASS}): "
              f"{', '.join(str(int(i)) for i in r.focus_sensors)}. Per-sensor mean (judged; "
              "upper table) and pooled over the ten traces (extra; lower table):", ""]
    for matrix in (r.similarity, r.similarity_pooled):
        lines += ["| | " + " | ".join(f"{i + 1} ({n})" for i, n in enumerate(names)) + " |",
                  "|---" * (len(names) + 1) + "|"]
        for i, n in enumerate(names):
            lines.append(f"| {i + 1} ({n}) | " + " | ".join(f"{v:.3f}" for v in matrix[i])
                         + " |")
        lines.append("")
    lines += _decoding_tables(r, config)
    lines += ["Compute time (s): " + ", ".join(f"{k} {v:.1f}" for k, v in r.seconds.items()),
              ""]
    return lines


def write_report(results: Sequence[MechanicsResults], regime: Regime, config: ReproduceConfig,
                 out: Path, total_s: float, quick: bool,
                 search: dict[str, Any] | None = None) -> Path:
    """Write ``REPORT.md`` (and ``results.json``) into ``out``; returns the report's path.
    ``search``: the paper preset's search (:mod:`skinhil.reproduce.paper_search`), if run."""
    d = config.decoding
    amps = ", ".join(f"{a} (M, K and C x{SKIN_AMPLITUDES[a]:g}"
                     + (": the default skin)" if a == DEFAULT_AMPLITUDE else ")")
                     for a in config.amplitudes)
    lines = ["# skinhil reproduction report", "",
             f"Run: {'--quick (small grids, few repeats)' if quick else 'full'}; "
             f"{total_s:.1f} s in total. Model: `SkinParams.at_amplitude(amplitude)` defaults "
             "(only `mechanics`, `readout` and the amplitude differ: a 2 x 2 x 2 design whose "
             "swaps name the "
             f"cause of each outcome); amplitudes: {amps}: scaling mass, stiffness and "
             "damping together keeps the modes, damping ratios and the linear model's "
             "spring forces and divides every strain by the factor. Nothing tuned per "
             "figure. Definitions and choices: docs/reproduce.md.", "",
             f"Decoding: {d.reps} trials per condition, {d.folds}-fold cross-validation x "
             f"{d.repeats} repeats, features {d.spec.window_s * 1e3:g} ms from the onset in "
             f"{d.spec.bin_s * 1e3:g} ms bins of the chosen sensors, seed {d.seed}; three "
             f"feature sets: the paper's sensor #5 of M{FOCUS_MASS} alone (every one of its "
             f"ten sensors alone in the per-sensor table), M{FOCUS_MASS}'s ten sensors, all "
             "338.", "", "## Claims of the paper", ""]
    lines += _claims_table(results)
    lines += ["Thresholds and rules fixed in advance (skinhil/reproduce/claims.py, each with a "
              "passing and a failing test on made-up numbers): 1E-F (stimulus 1, as the "
              "paper's Figure 1): nPC99 ratio ind/post above 1 and the area between the "
              "curves (ind − post, the paper's sign) negative; 2A (on the first grid): "
              f"extremes are the lowest {claims.EXTREME_FRACTION:.0%} of the damping values "
              f"and the highest {claims.EXTREME_FRACTION:.0%} of the stiffness values; the "
              "largest distance from the median area (of the points away from the extremes) "
              "lies at an extreme, and the 90th percentile of the distance away from them is "
              f"at most {claims.AREA_ELSEWHERE_MAX_SHARE:.0%} of it; 2B, 2C: the measure "
              "turns over in damping (its K-averaged profile's ends both at least "
              f"{claims.TURNOVER_MIN_DROP:.0%} below its largest value, on a damping grid "
              f"extended by {EXTENSION_DECADES:g} decade past any end it peaks at, at most "
              f"{config.extensions} times), and the nPC ratio's optimum (the centroid of "
              f"each map's top {1 - claims.OPTIMUM_TOP_QUANTILE:.0%}) lies at lower K than "
              "the SIR ratio's by at least "
              f"{claims.MIN_SEPARATION_DECADES:g} decade (2B: the nPC ratio turns over; 2C: "
              "the SIR ratio turns over): no tie order and no grid edge decides; 3F: inputs "
              "2-3 the strict maximum over distinct pairs of the per-sensor mean index (as "
              f"the paper; pooled shown); 4F: the paper's sensor at {FIGURE_SNR_DB:g} dB "
              f"between {claims.WELL_ABOVE_CHANCE:g}x chance and {claims.WELL_BELOW_FULL:g}, "
              f"and at least {claims.RESPONSE_FLOOR_SPIKES:g} spike per trial in every "
              f"condition; 4G: Spearman rho of accuracy with SNR above {claims.RISING_MIN_RHO} "
              "and the noise-free accuracy above the lowest SNR's. The likely cause of a claim "
              "not reproduced is read off the design: the factors (dynamics, readout, "
              "amplitude) whose swap alone reproduces it; else the pair of swaps that does.",
              ""]
    lines += _where_lines(results)
    lines += search_lines(search)
    lines += _regime_lines(regime)
    for r in results:
        lines += _mechanics_section(r, config)
    lines += ["## Figures", ""] + [f"- [{k}]({k}): {v}" for k, v in FIGURES.items()] + [""]
    write_text(out / "results.json", json.dumps(_json(results, regime, total_s, search),
                                                indent=1, allow_nan=True))
    return write_text(out / "REPORT.md", "\n".join(lines))


def _cv_json(snrs: Sequence[float], results: Sequence[CVResult]) -> list[dict[str, Any]]:
    return [{"snr_db": s if math.isfinite(s) else "inf", "accuracy": c.accuracy,
             "accuracy_std": c.accuracy_std, "confusion": c.confusion.tolist()}
            for s, c in zip(snrs, results, strict=True)]


def _sweep_json(sw: SweepResult) -> dict[str, Any]:
    return {"stiffness_n_per_m": list(sw.spec.stiffness_n_per_m),
            "damping_n_s_per_m": list(sw.spec.damping_n_s_per_m),
            "tension_n": list(sw.spec.tension_n),
            **{k: v.tolist() for k, v in sw.values.items()}}


def _json(results: Sequence[MechanicsResults], regime: Regime, total_s: float,
          search: dict[str, Any] | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {"total_s": total_s, "paper_search": search, "regime": {
        "relative_displacement": {m: {n: {"ratio": d.ratio, "spring": d.spring, "t_s": d.t_s}
                                      for n, d in per.items()}
                                  for m, per in regime.per_stimulus.items()},
        "valid_ratio": VALID_RATIO, "valid_force_n": regime.valid_force_n,
        "readout_gap_at_valid": regime.gap_at_valid,
        "readout_gap_at_paper": regime.gap_at_paper}}
    for r in results:
        out[r.label] = {
            "mechanics": r.mechanics,
            "readout": r.readout,
            "amplitude": r.amplitude,
            "params": {"mass_kg": r.params.mass_kg,
                       "stiffness_n_per_m": r.params.stiffness_n_per_m,
                       "damping_n_s_per_m": r.params.damping_n_s_per_m},
            "strain": {k: {"max": v.max, "median": v.median} for k, v in r.strain.items()},
            "measures": r.measures.as_dict(),
            "measures_stacked": r.stacked.as_dict(),
            "similarity_pooled": r.similarity_pooled.tolist(),
            "curve_indentation": r.pca_ind.curve[:50].tolist(),
            "curve_post_indentation": r.pca_post.curve[:50].tolist(),
            "similarity": r.similarity.tolist(),
            "sweep": _sweep_json(r.sweep),
            "sweep_first_grid_damping_n_s_per_m": list(r.sweep_base.spec.damping_n_s_per_m),
            **({"tension_x_stiffness": _sweep_json(r.tension_k),
                "tension_x_damping": _sweep_json(r.tension_c)} if r.tension_k.values else {}),
            "focus_sensors": [int(s) for s in r.focus_sensors],
            "paper_sensor": r.paper_sensor,
            "decoding": {name: _cv_json(r.snrs_db, res) for name, res in r.decoding.items()},
            "verdicts": [{"key": v.key, "claim": v.claim, "reproduced": v.reproduced,
                          "strain_max": claim_strain(r, v.key).max,
                          "strain_median": claim_strain(r, v.key).median,
                          "evidence": v.evidence, "reason": v.reason} for v, _ in verdicts(r)],
            "seconds": r.seconds,
        }
    return out
