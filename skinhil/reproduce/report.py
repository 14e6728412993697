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
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import paper_stimuli
from skinhil.output_files import write_text
from skinhil.reproduce import claims
from skinhil.reproduce.compute import (
    ALL_SET,
    FIGURE_SNR_DB,
    FIGURE_TRIAL_S,
    FOCUS_CONDITION,
    FOCUS_MASS,
    PAPER_SENSOR_RANK,
    TEN_SET,
    MechanicsResults,
    ReproduceConfig,
    sensor_set_name,
)
from skinhil.reproduce.figures import FIGURES

CLAIM_KEYS: tuple[str, ...] = ("1E-F", "2A", "2B", "2C", "3F", "4F", "4G")
"""The paper's claims checked, one REPORT.md row each per mechanics."""


def verdicts(r: MechanicsResults) -> list[tuple[claims.Verdict, str]]:
    """Each claim's verdict for one mechanics (order :data:`CLAIM_KEYS`), with the figure
    file that shows it."""
    names = [s.name for s in paper_stimuli()]
    out = [
        (claims.information_phases(r.measures), "fig1E_variance_explained.png"),
        (claims.area_flat_except_extremes(r.sweep), "fig2ABC_sweeps.png"),
        (claims.npc_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.sir_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.inputs_2_3_most_similar(r.similarity, names, _rms_at_focus(r)),
         "fig3F_similarity.png"),
        (claims.decoding_at_operating_point(r.snrs_db[r.figure_index],
                                            _headline(r.at_figure_snr(), r), r.paper_label),
         "fig4F_confusion.png"),
        (claims.decoding_rises_with_snr(r.snrs_db, _headline(r.decoding, r), r.paper_label),
         "fig4G_accuracy_vs_snr.png"),
    ]
    return out


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


def _claims_table(results: Sequence[MechanicsResults]) -> list[str]:
    lines = ["| panel | claim | mechanics | reproduced | evidence | likely reason if not | "
             "figure |", "|---|---|---|---|---|---|---|"]
    rows = {r.mechanics: verdicts(r) for r in results}
    for k in range(len(CLAIM_KEYS)):
        for r in results:
            v, fig = rows[r.mechanics][k]
            lines.append(f"| {v.key} | {v.claim} | {r.mechanics} | "
                         f"{'yes' if v.reproduced else '**no**'} | {v.evidence} | "
                         f"{v.reason or '—'} | [{fig}]({fig}) |")
    counts = ", ".join(f"{r.mechanics} **{sum(v.reproduced for v, _ in rows[r.mechanics])} "
                       f"of {len(CLAIM_KEYS)}**" for r in results)
    return lines + ["", f"Claims reproduced: {counts}. The default mechanics is chosen from "
                    "these counts and the board's real-time budget: see "
                    "`skinhil/model/skin.py` and the README.", ""]


def _decoding_tables(r: MechanicsResults, config: ReproduceConfig) -> list[str]:
    snrs = r.snrs_db
    head = "| feature set | " + " | ".join(f"{_snr(s)} dB" for s in snrs) + " |"
    rule = "|---" * (len(snrs) + 1) + "|"
    lines = [f"### Decoding the 9 direction conditions (Fig 4D-G), {r.mechanics}", "",
             "Accuracy (mean over the test folds) per feature set and SNR:", "", head, rule]
    for label, res in _headline(r.decoding, r).items():
        lines.append(f"| {label} | " + " | ".join(f"{cv.accuracy:.3f}" for cv in res) + " |")
    model = SkinModel(SkinParams(mechanics=r.mechanics))  # type: ignore[arg-type]
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
    trials = r.sensor_trials[..., int(np.flatnonzero(r.focus_sensors == r.paper_sensor)[0])]
    counts = trials.sum(axis=2).mean(axis=1)
    lines += ["", f"Rasters (Fig 4D-E): the decoding's own {trials.shape[1]} trials per "
              f"condition at {FIGURE_SNR_DB:g} dB, run for {FIGURE_TRIAL_S:g} s. Spikes per "
              f"trial of sensor {r.paper_sensor} per condition 0..8: "
              + ", ".join(f"{c:.1f}" for c in counts) + ". Fig 4C is one trial of condition "
              f"{FOCUS_CONDITION} ({int(r.population_raster.sum())} spikes over all "
              "sensors).", ""]
    return lines


def _sweep_lines(sw: SweepResult) -> list[str]:
    lines = [f"Stiffness K {sw.spec.stiffness_n_per_m[0]:g}..{sw.spec.stiffness_n_per_m[-1]:g}"
             f" N/m x damping C {sw.spec.damping_n_s_per_m[0]:g}.."
             f"{sw.spec.damping_n_s_per_m[-1]:g} N·s/m (log-spaced, {sw.spec.shape[1]} x "
             f"{sw.spec.shape[2]}), {sw.seconds:.1f} s.", "",
             "| measure | min | median | max | NaN points |", "|---|---|---|---|---|"]
    for name in ("area", "npc_ratio", "sir_ratio", "npc99_ind", "npc99_post", "sir_ind",
                 "sir_post"):
        v = sw.at(name)
        finite = v[np.isfinite(v)]
        stats = [_num(float(f(finite))) if finite.size else "NaN"
                 for f in (np.min, np.median, np.max)]
        lines.append(f"| {name} | {' | '.join(stats)} | {int(np.isnan(v).sum())} |")
    lines += ["", "Mean per tercile block (rows: K low, mid, high; columns: C low, mid, high):",
              ""]
    for name in ("area", "npc_ratio", "sir_ratio"):
        m = claims.tercile_means(sw.at(name))
        rows = ["/".join(_num(float(x)) for x in row) for row in m]
        lines.append(f"- {name}: K low {rows[0]}; K mid {rows[1]}; K high {rows[2]}")
    return lines + [""]


def _tension_lines(r: MechanicsResults) -> list[str]:
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
    m = r.measures
    names = [s.name for s in paper_stimuli()]
    lines = [f"## {r.mechanics} mechanics", "",
             "### Information content at the default parameters (Fig 1E-F)", "",
             "| measure | indentation | post-indentation | ratio ind/post |",
             "|---|---|---|---|",
             f"| nPC for 99% variance | {_num(m.npc99_ind)} | {_num(m.npc99_post)} | "
             f"{_num(m.npc_ratio)} |",
             f"| signal-information ratio (PC1-{N_SIR_COMPONENTS}) | {_num(m.sir_ind)} | "
             f"{_num(m.sir_post)} | {_num(m.sir_ratio)} |", "",
             f"Area between the variance-explained curves (post − ind, in PCs): "
             f"**{_num(m.area)}**. Variance explained by PC1-3: indentation "
             f"{_num(float(r.pca_ind.curve[2]))}, post-indentation "
             f"{_num(float(r.pca_post.curve[2]))}.", "",
             "### Sweep of stiffness x damping (Fig 2A-C)", ""]
    lines += _sweep_lines(r.sweep)
    lines += _tension_lines(r)
    lines += [f"### Correlation index between the inputs at M{FOCUS_MASS}'s sensors (Fig 3F)",
              "", f"Sensors (springs attached to M{FOCUS_MASS}): "
              f"{', '.join(str(int(i)) for i in r.focus_sensors)}.", "",
              "| | " + " | ".join(f"{i + 1} ({n})" for i, n in enumerate(names)) + " |",
              "|---" * (len(names) + 1) + "|"]
    for i, n in enumerate(names):
        lines.append(f"| {i + 1} ({n}) | " + " | ".join(f"{v:.3f}" for v in r.similarity[i])
                     + " |")
    lines += [""] + _decoding_tables(r, config)
    lines += ["Compute time (s): " + ", ".join(f"{k} {v:.1f}" for k, v in r.seconds.items()),
              ""]
    return lines


def write_report(results: Sequence[MechanicsResults], config: ReproduceConfig, out: Path,
                 total_s: float, quick: bool) -> Path:
    """Write ``REPORT.md`` (and ``results.json``) into ``out``; returns the report's path."""
    d = config.decoding
    lines = ["# skinhil reproduction report", "",
             f"Run: {'--quick (small grids, few repeats)' if quick else 'full'}; "
             f"{total_s:.1f} s in total. Model: `SkinParams()` defaults for both mechanics "
             "(only `mechanics` differs); nothing tuned per figure. Definitions and choices: "
             "docs/reproduce.md.", "",
             f"Decoding: {d.reps} trials per condition, {d.folds}-fold cross-validation x "
             f"{d.repeats} repeats, features {d.spec.window_s * 1e3:g} ms from the onset in "
             f"{d.spec.bin_s * 1e3:g} ms bins of the chosen sensors, seed {d.seed}; three "
             f"feature sets: the paper's sensor #5 of M{FOCUS_MASS} alone (every one of its "
             f"ten sensors alone in the per-sensor table), M{FOCUS_MASS}'s ten sensors, all "
             "338.", "", "## Claims of the paper", ""]
    lines += _claims_table(results)
    lines += ["Thresholds and rules fixed in advance (skinhil/reproduce/claims.py): 2A: "
              f"extremes are the lowest {claims.EXTREME_FRACTION:.0%} of the damping values and "
              f"the highest {claims.EXTREME_FRACTION:.0%} of the stiffness values, and 'varies "
              f"little' means the range elsewhere is at most "
              f"{claims.AREA_ELSEWHERE_MAX_SHARE:.0%} of the whole grid's range; 2B, 2C: the "
              "tercile block (K x C) with the highest mean of the measure; 3F: inputs 2-3 the "
              "strict maximum of the index over distinct pairs; 4F: the paper's sensor at "
              f"{FIGURE_SNR_DB:g} dB between {claims.WELL_ABOVE_CHANCE:g}x chance and "
              f"{claims.WELL_BELOW_FULL:g}; 4G: Spearman rho of accuracy with SNR above "
              f"{claims.RISING_MIN_RHO} and the noise-free accuracy above the lowest SNR's.", ""]
    for r in results:
        lines += _mechanics_section(r, config)
    lines += ["## Figures", ""] + [f"- [{k}]({k}): {v}" for k, v in FIGURES.items()] + [""]
    write_text(out / "results.json", json.dumps(_json(results, total_s), indent=1,
                                                allow_nan=True))
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


def _json(results: Sequence[MechanicsResults], total_s: float) -> dict[str, Any]:
    out: dict[str, Any] = {"total_s": total_s}
    for r in results:
        out[r.mechanics] = {
            "measures": r.measures.as_dict(),
            "curve_indentation": r.pca_ind.curve[:50].tolist(),
            "curve_post_indentation": r.pca_post.curve[:50].tolist(),
            "similarity": r.similarity.tolist(),
            "sweep": _sweep_json(r.sweep),
            "tension_x_stiffness": _sweep_json(r.tension_k),
            "tension_x_damping": _sweep_json(r.tension_c),
            "focus_sensors": [int(s) for s in r.focus_sensors],
            "paper_sensor": r.paper_sensor,
            "decoding": {name: _cv_json(r.snrs_db, res) for name, res in r.decoding.items()},
            "verdicts": [{"key": v.key, "claim": v.claim, "reproduced": v.reproduced,
                          "evidence": v.evidence, "reason": v.reason} for v, _ in verdicts(r)],
            "seconds": r.seconds,
        }
    return out
