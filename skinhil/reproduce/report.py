"""REPORT.md and results.json of ``skinhil reproduce``: every number, every claim's verdict."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.analysis.pca import N_SIR_COMPONENTS
from skinhil.reproduce import claims
from skinhil.reproduce.compute import (
    FIGURE_SNR_DB,
    FOCUS_CONDITION,
    FOCUS_MASS,
    MechanicsResults,
    ReproduceConfig,
)
from skinhil.reproduce.figures import FIGURES
from skinhil.stimuli import paper_stimuli


def verdicts(r: MechanicsResults) -> list[tuple[claims.Verdict, str]]:
    """Each claim's verdict for one mechanics, with the figure file that shows it."""
    names = [s.name for s in paper_stimuli()]
    return [
        (claims.information_phases(r.measures), "fig1E_variance_explained.png"),
        (claims.sweep_dependence(r.sweep), "fig2ABC_sweeps.png"),
        (claims.dissimilar_responses(r.similarity, names), "fig3F_similarity.png"),
        (claims.decoding_above_chance(r.snrs_db, r.decoding), "fig4F_confusion.png"),
        (claims.decoding_rises_with_snr(r.snrs_db, r.decoding), "fig4G_accuracy_vs_snr.png"),
    ]


def _num(v: float) -> str:
    return "NaN" if isinstance(v, float) and math.isnan(v) else f"{v:.4g}"


def _mechanics_section(r: MechanicsResults) -> list[str]:
    m = r.measures
    sw = r.sweep
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
             f"### Sweep, {sw.spec.shape[1]} x {sw.spec.shape[2]} grid (Fig 2A-C)", "",
             f"Stiffness K {sw.spec.stiffness_n_per_m[0]:g}..{sw.spec.stiffness_n_per_m[-1]:g}"
             f" N/m x damping C {sw.spec.damping_n_s_per_m[0]:g}.."
             f"{sw.spec.damping_n_s_per_m[-1]:g} N·s/m (log-spaced), {sw.seconds:.1f} s.", "",
             "| measure | min | median | max | NaN points |", "|---|---|---|---|---|"]
    for name in ("area", "npc_ratio", "sir_ratio", "npc99_ind", "npc99_post", "sir_ind",
                 "sir_post"):
        v = sw.at(name)
        finite = v[np.isfinite(v)]
        stats = [_num(float(f(finite))) if finite.size else "NaN"
                 for f in (np.min, np.median, np.max)]
        lines.append(f"| {name} | {' | '.join(stats)} | {int(np.isnan(v).sum())} |")
    lines += ["", f"### Similarity across stimuli at M{FOCUS_MASS}'s sensors (Fig 3F)", "",
              f"Sensors (springs attached to M{FOCUS_MASS}): "
              f"{', '.join(str(int(i)) for i in r.focus_sensors)}.", "",
              "| | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    for i, n in enumerate(names):
        lines.append(f"| {n} | " + " | ".join(f"{v:.3f}" for v in r.similarity[i]) + " |")
    lines += ["", "### Decoding the 9 direction conditions (Fig 4F-G)", "",
              "| SNR (dB) | accuracy | std | folds x repeats |", "|---|---|---|---|"]
    for snr, cv in zip(r.snrs_db, r.decoding, strict=True):
        lines.append(f"| {snr:g} | {cv.accuracy:.3f} | {cv.accuracy_std:.3f} | "
                     f"{cv.folds} x {cv.repeats} |")
    cv = r.decoding[r.confusion_index]
    lines += ["", f"Confusion matrix at {r.snrs_db[r.confusion_index]:g} dB (rows: true "
              "condition, columns: predicted; fraction of trials):", "",
              "| | " + " | ".join(str(c) for c in cv.classes) + " |",
              "|---" * (len(cv.classes) + 1) + "|"]
    for i, c in enumerate(cv.classes):
        lines.append(f"| {c} | " + " | ".join(f"{v:.2f}" for v in cv.confusion_fraction[i])
                     + " |")
    lines += ["", f"Raster (Fig 4C-E): condition {FOCUS_CONDITION}, {r.rasters.shape[0]} "
              f"repetitions at {FIGURE_SNR_DB:g} dB; sensor {r.raster_sensor} (the sensor of "
              f"M{FOCUS_MASS} with the largest tension) fired "
              f"{r.rasters[:, :, r.raster_sensor].sum() / r.rasters.shape[0]:.1f} spikes per "
              "trial.", "",
              "Compute time (s): " + ", ".join(f"{k} {v:.1f}" for k, v in r.seconds.items()), ""]
    return lines


def write_report(results: Sequence[MechanicsResults], config: ReproduceConfig, out: Path,
                 total_s: float, quick: bool) -> Path:
    """Write ``REPORT.md`` (and ``results.json``) into ``out``; returns the report's path."""
    d = config.decoding
    lines = ["# skinhil reproduction report", "",
             f"Run: {'--quick (small grids, few repeats)' if quick else 'full'}; "
             f"{total_s:.1f} s in total. Model: `SkinParams()` defaults for both mechanics; "
             "nothing tuned per figure. Definitions and choices: docs/reproduce.md.", "",
             f"Decoding: {d.reps} trials per condition, {d.folds}-fold cross-validation x "
             f"{d.repeats} repeats, features {d.spec.window_s * 1e3:g} ms window in "
             f"{d.spec.bin_s * 1e3:g} ms bins of all {d.spec.n_channels} sensors, seed "
             f"{d.seed}.", "", "## Claims of the paper", "",
             "| claim | mechanics | reproduced | evidence | likely reason if not | figure |",
             "|---|---|---|---|---|---|"]
    for r in results:
        for v, fig in verdicts(r):
            lines.append(f"| {v.claim} | {r.mechanics} | {'yes' if v.reproduced else '**no**'}"
                         f" | {v.evidence} | {v.reason or '—'} | [{fig}]({fig}) |")
    lines += ["", "Thresholds fixed in advance (skinhil/reproduce/claims.py): a measure changes "
              f"over the grid if its range exceeds {claims.SWEEP_MIN_SPREAD:.0%} of its median; "
              f"responses are dissimilar if the mean pair similarity is below "
              f"{claims.DISSIMILAR_BELOW}; well above chance is {claims.WELL_ABOVE_CHANCE:g}x "
              f"chance; rising means a Spearman rho above {claims.RISING_MIN_RHO}.", ""]
    for r in results:
        lines += _mechanics_section(r)
    lines += ["## Figures", ""] + [f"- [{k}]({k}): {v}" for k, v in FIGURES.items()] + [""]
    path = out / "REPORT.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    (out / "results.json").write_text(json.dumps(_json(results, total_s), indent=1,
                                                 allow_nan=True), encoding="utf-8")
    return path


def _json(results: Sequence[MechanicsResults], total_s: float) -> dict[str, Any]:
    out: dict[str, Any] = {"total_s": total_s}
    for r in results:
        out[r.mechanics] = {
            "measures": r.measures.as_dict(),
            "curve_indentation": r.pca_ind.curve[:50].tolist(),
            "curve_post_indentation": r.pca_post.curve[:50].tolist(),
            "similarity": r.similarity.tolist(),
            "sweep": {"stiffness_n_per_m": list(r.sweep.spec.stiffness_n_per_m),
                      "damping_n_s_per_m": list(r.sweep.spec.damping_n_s_per_m),
                      **{k: v[0].tolist() for k, v in r.sweep.values.items()}},
            "decoding": [{"snr_db": s if math.isfinite(s) else "inf", "accuracy": c.accuracy,
                          "accuracy_std": c.accuracy_std, "confusion": c.confusion.tolist()}
                         for s, c in zip(r.snrs_db, r.decoding, strict=True)],
            "verdicts": [{"claim": v.claim, "reproduced": v.reproduced, "evidence": v.evidence,
                          "reason": v.reason} for v, _ in verdicts(r)],
            "seconds": r.seconds,
        }
    return out
