"""The paper's claims, checked against computed numbers with thresholds fixed in advance.

Each check returns a :class:`Verdict`: whether the numbers support the claim, what they are,
and, when they do not, the likely reason. Thresholds (named constants below) were set before
looking at any result and are the same for both mechanics.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import spearmanr

from skinhil.analysis.information import InformationMeasures
from skinhil.analysis.sweep import SweepResult
from skinhil.decoding import CVResult

SWEEP_MIN_SPREAD = 0.10
"""A measure 'changes with K and C' if its range over the grid exceeds 10% of its median
magnitude."""
DISSIMILAR_BELOW = 0.5
"""Responses are 'dissimilar' if the mean similarity of distinct stimulus pairs is below
this."""
WELL_ABOVE_CHANCE = 3.0
"""'Well above chance' means at least this many times the chance accuracy (1/9)."""
RISING_MIN_RHO = 0.8
"""'Rising with SNR' needs a Spearman rank correlation of accuracy with SNR above this."""


@dataclass(frozen=True)
class Verdict:
    """``reproduced`` (True/False), ``evidence`` (numbers, one line) and ``reason`` (why not)."""

    claim: str
    reproduced: bool
    evidence: str
    reason: str = ""


def information_phases(m: InformationMeasures) -> Verdict:
    """Claim: the indentation phase carries more information than the post-indentation one."""
    claim = "information content is higher during indentation than after it (Fig 1E-F)"
    ok = m.npc_ratio > 1 and m.area > 0
    evidence = (f"nPC99 indentation {m.npc99_ind:g} vs post {m.npc99_post:g} (ratio "
                f"{m.npc_ratio:.3g}); area between curves {m.area:.3g}; SIR ind "
                f"{m.sir_ind:.3g} vs post {m.sir_post:.3g}")
    reason = ""
    if not ok:
        if math.isnan(m.npc_ratio):
            reason = "a phase has no variance at all (silent), so the measures are undefined"
        else:
            reason = ("after release the mesh rings freely in its own modes, unconstrained by "
                      "the force, which spreads the variance over more components than the "
                      "force-following response during indentation")
    return Verdict(claim, ok, evidence, reason)


def _spread(values: np.ndarray) -> float:
    v = values[np.isfinite(values)]
    if v.size < 2:
        return math.nan
    return float((v.max() - v.min()) / max(abs(float(np.median(v))), 1e-12))


def _rho(values: np.ndarray, axis_values: np.ndarray) -> float:
    ok = np.isfinite(values)
    if ok.sum() < 3 or np.ptp(values[ok]) == 0:
        return math.nan
    return float(spearmanr(values[ok], axis_values[ok]).statistic)


def sweep_dependence(sweep: SweepResult) -> Verdict:
    """Claim: the stiffness K and damping C change the information measures (Fig 2)."""
    claim = "spring stiffness K and damping C change the information measures (Fig 2A-C)"
    k_grid, c_grid = np.meshgrid(sweep.spec.stiffness_n_per_m, sweep.spec.damping_n_s_per_m,
                                 indexing="ij")
    parts, ok = [], True
    for name in ("area", "npc_ratio", "sir_ratio"):
        v = sweep.at(name)
        spread = _spread(v)
        ok = ok and spread > SWEEP_MIN_SPREAD
        parts.append(f"{name}: range {np.nanmin(v):.3g}..{np.nanmax(v):.3g}, "
                     f"rank corr. with K {_rho(v.ravel(), k_grid.ravel()):+.2f}, "
                     f"with C {_rho(v.ravel(), c_grid.ravel()):+.2f}")
    n_nan = int(np.isnan(sweep.at("area")).sum())
    if n_nan:
        parts.append(f"{n_nan} grid point(s) diverged (NaN)")
    reason = "" if ok else "a measure stays within 10% over the grid"
    return Verdict(claim, ok, "; ".join(parts), reason)


def dissimilar_responses(similarity: np.ndarray, names: Sequence[str]) -> Verdict:
    """Claim: the 5 stimuli evoke dissimilar responses at M15's sensors (Fig 3F)."""
    claim = "the paper stimuli evoke dissimilar responses at M15's sensors (Fig 3F)"
    off = similarity[~np.eye(similarity.shape[0], dtype=bool)]
    mean = float(np.nanmean(off))
    i, j = np.unravel_index(np.nanargmax(np.where(np.eye(len(names), dtype=bool), np.nan,
                                                  similarity)), similarity.shape)
    ok = mean < DISSIMILAR_BELOW
    evidence = (f"mean similarity of distinct pairs {mean:.3f} (range {np.nanmin(off):.3f}.."
                f"{np.nanmax(off):.3f}; most similar: {names[int(i)]}-{names[int(j)]})")
    reason = "" if ok else ("stimuli that push M15 the same way (e.g. normal presses on M15 "
                            "alone and spread over its neighbours) load its springs alike")
    return Verdict(claim, ok, evidence, reason)


def decoding_above_chance(snrs: Sequence[float], results: Sequence[CVResult]) -> Verdict:
    """Claim: decoding accuracy is well above chance (1/9)."""
    claim = "direction decoding is well above chance, 1/9 (Fig 4F-G)"
    chance = 1.0 / 9.0
    acc = [r.accuracy for r in results]
    finite = [a for s, a in zip(snrs, acc, strict=True) if math.isfinite(s)] or acc
    best = max(finite)
    above = [f"{s:g}" for s, r in zip(snrs, results, strict=True)
             if r.accuracy >= WELL_ABOVE_CHANCE * chance]
    ok = best >= WELL_ABOVE_CHANCE * chance
    evidence = (f"best accuracy at a finite SNR {best:.3f} (chance {chance:.3f}); "
                f"at least {WELL_ABOVE_CHANCE:g}x chance at SNR {', '.join(above) or 'none'} dB")
    reason = "" if ok else ("the neuron noise (measured from the membrane potential, which is "
                            "large at rest) swamps the few evoked spikes")
    return Verdict(claim, ok, evidence, reason)


def decoding_rises_with_snr(snrs: Sequence[float], results: Sequence[CVResult]) -> Verdict:
    """Claim: decoding accuracy rises with SNR (Fig 4G)."""
    claim = "decoding accuracy rises with the SNR (Fig 4G)"
    acc = np.array([r.accuracy for r in results])
    rank_x = np.array([s if math.isfinite(s) else 1e9 for s in snrs])
    rho = float(spearmanr(rank_x, acc).statistic) if np.ptp(acc) > 0 else math.nan
    ok = bool(rho > RISING_MIN_RHO and acc[np.argmax(rank_x)] > acc[np.argmin(rank_x)])
    evidence = (f"accuracy {' → '.join(f'{a:.2f}' for a in acc)} over SNR "
                f"{', '.join(f'{s:g}' for s in snrs)} dB; Spearman rho {rho:.2f}")
    reason = "" if ok else "accuracy is saturated or flat over the SNR range"
    return Verdict(claim, ok, evidence, reason)
