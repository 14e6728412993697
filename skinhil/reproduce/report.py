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

CLAIM_KEYS: tuple[str, ...] = ("1E-F", "2A", "2B", "2C", "3F", "4F", "4G")
"""The paper's claims checked, one REPORT.md row each per mechanics and readout."""
OTHER = {"linear": "geometric", "geometric": "linear", "length": "axial", "axial": "length"}


def verdicts(r: MechanicsResults) -> list[tuple[claims.Verdict, str]]:
    """Each claim's verdict for one mechanics (order :data:`CLAIM_KEYS`), with the figure
    file that shows it."""
    names = [s.name for s in paper_stimuli()]
    out = [
        (claims.information_phases(r.measures), "fig1E_variance_explained.png"),
        (claims.area_flat_except_extremes(r.sweep_base), "fig2ABC_sweeps.png"),
        (claims.npc_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.sir_ratio_region(r.sweep), "fig2ABC_sweeps.png"),
        (claims.inputs_2_3_most_similar(r.similarity, names, _rms_at_focus(r)),
         "fig3F_similarity.png"),
        (claims.decoding_at_operating_point(r.snrs_db[r.figure_index],
                                            _headline(r.at_figure_snr(), r), r.paper_label,
                                            r.paper_sensor_spikes),
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


def likely_cause(outcome: dict[tuple[str, str], bool], mechanics: str, readout: str) -> str:
    """The cause of a claim not reproduced by ``mechanics`` with ``readout``, named from the
    run's 2 x 2 experiment (``outcome`` maps (mechanics, readout) → reproduced): what one
    swap, with the other factor held fixed, changes. Rule fixed in advance; empty if
    reproduced or if the other combinations were not run."""
    if outcome.get((mechanics, readout), True):
        return ""
    m2, r2 = OTHER[mechanics], OTHER[readout]
    keys = ((mechanics, r2), (m2, readout), (m2, r2))
    if not all(k in outcome for k in keys):
        return ""
    by_readout, by_dynamics, by_both = (outcome[k] for k in keys)
    if by_readout and by_dynamics:
        return (f"either factor: the {mechanics} dynamics with the {r2} readout and the {m2} "
                f"dynamics with the {readout} readout both reproduce it")
    if by_readout:
        return (f"the readout: the same {mechanics} dynamics with the {r2} readout reproduce "
                "it")
    if by_dynamics:
        return (f"the dynamics: the {m2} dynamics with the same {readout} readout reproduce "
                "it")
    if by_both:
        return (f"both together: only the {m2} dynamics with the {r2} readout reproduce it")
    return "neither: no mechanics/readout combination of this run reproduces it"


def _outcomes(results: Sequence[MechanicsResults]
              ) -> dict[str, dict[tuple[str, str], bool]]:
    """Claim key → (mechanics, readout) → reproduced."""
    out: dict[str, dict[tuple[str, str], bool]] = {k: {} for k in CLAIM_KEYS}
    for r in results:
        for v, _ in verdicts(r):
            out[v.key][(r.mechanics, r.readout)] = v.reproduced
    return out


def claim_counts(results: Sequence[MechanicsResults]) -> dict[str, int]:
    """Label (mechanics/readout) → claims reproduced."""
    return {r.label: sum(v.reproduced for v, _ in verdicts(r)) for r in results}


def _claims_table(results: Sequence[MechanicsResults]) -> list[str]:
    lines = ["| panel | claim | mechanics | readout | reproduced | evidence | what failed | "
             "likely cause (this run's swap experiment) | figure |",
             "|---|---|---|---|---|---|---|---|---|"]
    rows = {r.label: verdicts(r) for r in results}
    outcomes = _outcomes(results)
    for k, key in enumerate(CLAIM_KEYS):
        for r in results:
            v, fig = rows[r.label][k]
            cause = likely_cause(outcomes[key], r.mechanics, r.readout)
            lines.append(f"| {v.key} | {v.claim} | {r.mechanics} | {r.readout} | "
                         f"{'yes' if v.reproduced else '**no**'} | {v.evidence} | "
                         f"{v.reason or '—'} | {cause or '—'} | [{fig}]({fig}) |")
    counts = ", ".join(f"{label} **{n} of {len(CLAIM_KEYS)}**"
                       for label, n in claim_counts(results).items())
    return lines + ["", f"Claims reproduced: {counts}. The default mechanics is chosen from "
                    "these counts and the board's real-time budget: see "
                    "`skinhil/model/skin.py` and the README.", ""]


def _regime_lines(regime: Regime) -> list[str]:
    names = list(next(iter(regime.per_stimulus.values())))
    mechs = list(regime.per_stimulus)
    lines = ["## Regime: how large the deformation is", "",
             "Largest relative displacement |q_j − q_i| / L0 of any spring (its ends' relative "
             "displacement over its rest length) at the default parameters, per stimulus "
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
              "lies far beyond it, in both mechanics.", ""]
    return lines


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
    counts = r.paper_sensor_spikes
    lines += ["", f"Rasters (Fig 4D-E): the decoding's own {r.sensor_trials.shape[1]} trials per "
              f"condition at {FIGURE_SNR_DB:g} dB, run for {FIGURE_TRIAL_S:g} s. Spikes per "
              f"trial of sensor {r.paper_sensor} per condition 0..8: "
              + ", ".join(f"{c:.1f}" for c in counts) + ". Fig 4C is one trial of condition "
              f"{FOCUS_CONDITION} ({int(r.population_raster.sum())} spikes over all "
              "sensors).", ""]
    return lines


def _sweep_lines(sw: SweepResult, first: SweepResult, extensions: int) -> list[str]:
    c0, c1 = first.spec.damping_n_s_per_m[0], first.spec.damping_n_s_per_m[-1]
    extended = ("" if sw.spec.damping_n_s_per_m == first.spec.damping_n_s_per_m else
                f" The first grid's damping ran {c0:g}..{c1:g} N·s/m; it was extended (by "
                f"{EXTENSION_DECADES:g} decade at a time, at most {extensions} times per "
                "end) where the K-averaged nPC or SIR ratio peaked at an end.")
    lines = [f"Stiffness K {sw.spec.stiffness_n_per_m[0]:g}..{sw.spec.stiffness_n_per_m[-1]:g}"
             f" N/m x damping C {sw.spec.damping_n_s_per_m[0]:g}.."
             f"{sw.spec.damping_n_s_per_m[-1]:g} N·s/m (log-spaced, {sw.spec.shape[1]} x "
             f"{sw.spec.shape[2]}), {sw.seconds:.1f} s.{extended}", "",
             "| measure | min | median | max | NaN points |", "|---|---|---|---|---|"]
    for name in ("area", "npc_ratio", "sir_ratio", "npc99_ind", "npc99_post", "sir_ind",
                 "sir_post"):
        v = sw.at(name)
        finite = v[np.isfinite(v)]
        stats = [_num(float(f(finite))) if finite.size else "NaN"
                 for f in (np.min, np.median, np.max)]
        lines.append(f"| {name} | {' | '.join(stats)} | {int(np.isnan(v).sum())} |")
    lines += ["", "Profile along damping, averaged over K (2B/2C's rule):", ""]
    for name in ("npc_ratio", "sir_ratio"):
        prof = claims.damping_profile(sw.at(name))
        lines.append(f"- {name}: " + ", ".join(
            f"{c:.3g}: {_num(float(p))}" for c, p in zip(sw.spec.damping_n_s_per_m, prof,
                                                         strict=True)))
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
    lines = [f"## {r.mechanics} mechanics, {r.readout} readout", "",
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
    lines += _sweep_lines(r.sweep, r.sweep_base, config.extensions)
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


def write_report(results: Sequence[MechanicsResults], regime: Regime, config: ReproduceConfig,
                 out: Path, total_s: float, quick: bool) -> Path:
    """Write ``REPORT.md`` (and ``results.json``) into ``out``; returns the report's path."""
    d = config.decoding
    lines = ["# skinhil reproduction report", "",
             f"Run: {'--quick (small grids, few repeats)' if quick else 'full'}; "
             f"{total_s:.1f} s in total. Model: `SkinParams()` defaults for both mechanics "
             "and both readouts (only `mechanics` and `readout` differ: a 2 x 2 design whose "
             "swaps name the cause of each outcome); nothing tuned per figure. Definitions "
             "and choices: docs/reproduce.md.", "",
             f"Decoding: {d.reps} trials per condition, {d.folds}-fold cross-validation x "
             f"{d.repeats} repeats, features {d.spec.window_s * 1e3:g} ms from the onset in "
             f"{d.spec.bin_s * 1e3:g} ms bins of the chosen sensors, seed {d.seed}; three "
             f"feature sets: the paper's sensor #5 of M{FOCUS_MASS} alone (every one of its "
             f"ten sensors alone in the per-sensor table), M{FOCUS_MASS}'s ten sensors, all "
             "338.", "", "## Claims of the paper", ""]
    lines += _claims_table(results)
    lines += ["Thresholds and rules fixed in advance (skinhil/reproduce/claims.py, each with a "
              "passing and a failing test on made-up numbers): 1E-F: nPC99 ratio ind/post "
              "above 1 and a positive area; 2A (on the first grid): extremes are the lowest "
              f"{claims.EXTREME_FRACTION:.0%} of the damping values and the highest "
              f"{claims.EXTREME_FRACTION:.0%} of the stiffness values; the largest distance "
              "from the median area (of the points away from the extremes) lies at an extreme, "
              "and the 90th percentile of the distance away from them is at most "
              f"{claims.AREA_ELSEWHERE_MAX_SHARE:.0%} of it (a map that varies across the whole "
              "grid fails, one flat but at the extremes passes); 2B, 2C: the measure's profile "
              "along damping, averaged over K, has an interior peak with both ends at least "
              f"{claims.TURNOVER_MIN_DROP:.0%} below it (ties: values within "
              f"{claims.TIE_RTOL:g} relative, the middle tied index wins), on a damping grid "
              f"extended by {EXTENSION_DECADES:g} decade past any end it peaks at (at most "
              f"{config.extensions} times in this run), and at that damping it peaks in the "
              "low (2B) or high (2C) K tercile; 3F: inputs 2-3 the strict maximum of the "
              f"index over distinct pairs; 4F: the paper's sensor at {FIGURE_SNR_DB:g} dB between "
              f"{claims.WELL_ABOVE_CHANCE:g}x chance and {claims.WELL_BELOW_FULL:g}, and at "
              f"least {claims.RESPONSE_FLOOR_SPIKES:g} spike per trial in every condition; 4G: "
              f"Spearman rho of accuracy with SNR above {claims.RISING_MIN_RHO} and the "
              "noise-free accuracy above the lowest SNR's. The likely cause of a claim not "
              "reproduced is read off the 2 x 2 run: the readout if the same dynamics with the "
              "other readout reproduce it, the dynamics if the other dynamics with the same "
              "readout do.", ""]
    lines += _regime_lines(regime)
    for r in results:
        lines += _mechanics_section(r, config)
    lines += ["## Figures", ""] + [f"- [{k}]({k}): {v}" for k, v in FIGURES.items()] + [""]
    write_text(out / "results.json", json.dumps(_json(results, regime, total_s), indent=1,
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


def _json(results: Sequence[MechanicsResults], regime: Regime,
          total_s: float) -> dict[str, Any]:
    out: dict[str, Any] = {"total_s": total_s, "regime": {
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
            "measures": r.measures.as_dict(),
            "curve_indentation": r.pca_ind.curve[:50].tolist(),
            "curve_post_indentation": r.pca_post.curve[:50].tolist(),
            "similarity": r.similarity.tolist(),
            "sweep": _sweep_json(r.sweep),
            "sweep_first_grid_damping_n_s_per_m": list(r.sweep_base.spec.damping_n_s_per_m),
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
