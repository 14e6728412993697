"""The paper's claims, checked against computed numbers with thresholds fixed in advance.

Each check returns a :class:`Verdict`: whether the numbers support the claim, what they are,
and, when they do not, the likely reason. The thresholds (named constants below) and the
rules were written before any result of the run they judge, and are the same for both
mechanics. One row of REPORT.md per claim and mechanics: 1E-F, 2A, 2B, 2C, 3F, 4F, 4G.

Where a claim names a region of the K x C sweep ("high compliance", "intermediate damping")
the grid is cut into **terciles** along each axis (its log-spaced values split into three
consecutive, nearly equal groups: low, mid, high) and the claim names the tercile block
(K tercile, C tercile) with the highest mean of the measure. High compliance is low K.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import spearmanr

from skinhil.analysis.decoding_snr import CHANCE
from skinhil.analysis.information import InformationMeasures
from skinhil.analysis.sweep import SweepResult
from skinhil.decoding import CVResult

TERCILES: tuple[str, str, str] = ("low", "mid", "high")
EXTREME_FRACTION = 0.2
"""2A: 'extremely low damping' is the lowest 20 % of the damping grid values (at least
one), 'extremely high stiffness' the highest 20 % of the stiffness values."""
AREA_ELSEWHERE_MAX_SHARE = 0.25
"""2A: the area 'varies little' elsewhere if its range outside those extremes is at most
25 % of its range over the whole grid."""
WELL_ABOVE_CHANCE = 3.0
"""'Well above chance' means at least this many times the chance accuracy (1/9)."""
WELL_BELOW_FULL = 0.9
"""'Well below 100 %' means an accuracy of at most 0.9 (one trial in ten or more wrong)."""
RISING_MIN_RHO = 0.8
"""'Rising with SNR' needs a Spearman rank correlation of accuracy with SNR above this, and
the noise-free accuracy above the lowest SNR's."""


@dataclass(frozen=True)
class Verdict:
    """One claim's check: ``key`` (the paper's panel, e.g. "2B"), the ``claim``, whether it is
    ``reproduced``, the ``evidence`` (numbers, one line) and the ``reason`` when it is not."""

    key: str
    claim: str
    reproduced: bool
    evidence: str
    reason: str = ""


def information_phases(m: InformationMeasures) -> Verdict:
    """1E-F: the indentation phase spreads its variance over more components than the
    post-indentation phase (nPC99 ratio above 1 and a positive area between the curves)."""
    claim = "more information during indentation than after it"
    ok = m.npc_ratio > 1 and m.area > 0
    evidence = (f"nPC99 indentation {m.npc99_ind:g} vs post {m.npc99_post:g} (ratio "
                f"{m.npc_ratio:.3g}); area between curves {m.area:.3g}; SIR ind "
                f"{m.sir_ind:.3g} vs post {m.sir_post:.3g}")
    reason = ""
    if not ok:
        if math.isnan(m.npc_ratio):
            reason = "a phase has no variance at all (silent), so the measures are undefined"
        else:
            reason = ("during indentation the mesh follows the force quasi-statically, one "
                      "spatial pattern per input; after release it rings freely in its own "
                      "modes, which spreads the variance over more components; only "
                      "large-deformation coupling adds components during indentation")
    return Verdict("1E-F", claim, ok, evidence, reason)


def tercile_groups(n: int) -> list[np.ndarray]:
    """Grid indices 0..n-1 split into the low, mid and high terciles (empty if n < 3)."""
    return [np.asarray(g, dtype=np.int64) for g in np.array_split(np.arange(n), 3)]


def tercile_means(values: np.ndarray) -> np.ndarray:
    """(3, 3) mean of a (n_K, n_C) map per (K tercile, C tercile) block (NaN: empty block or
    no finite value)."""
    v = np.asarray(values, dtype=float)
    out = np.full((3, 3), np.nan)
    for i, gk in enumerate(tercile_groups(v.shape[0])):
        for j, gc in enumerate(tercile_groups(v.shape[1])):
            block = v[np.ix_(gk, gc)]
            if np.isfinite(block).any():
                out[i, j] = float(np.nanmean(block))
    return out


def best_tercile(values: np.ndarray) -> tuple[str, str] | None:
    """(K tercile, C tercile) of the block with the highest mean; None if undefined."""
    means = tercile_means(values)
    if not np.isfinite(means).all():
        return None
    i, j = np.unravel_index(int(np.argmax(means)), means.shape)
    return TERCILES[int(i)], TERCILES[int(j)]


def _where_max(sweep: SweepResult, name: str) -> str:
    v = sweep.at(name)
    if not np.isfinite(v).any():
        return "no finite value"
    i, j = np.unravel_index(int(np.nanargmax(v)), v.shape)
    k, c = sweep.spec.stiffness_n_per_m[i], sweep.spec.damping_n_s_per_m[j]
    groups = [tercile_groups(n) for n in v.shape]
    tk = next((TERCILES[t] for t, g in enumerate(groups[0]) if i in g), "?")
    tc = next((TERCILES[t] for t, g in enumerate(groups[1]) if j in g), "?")
    return f"grid maximum {v[i, j]:.3g} at K {k:.3g} N/m ({tk}), C {c:.3g} N·s/m ({tc})"


def _tercile_claim(sweep: SweepResult, name: str, key: str, claim: str,
                   want: tuple[str, str]) -> Verdict:
    best = best_tercile(sweep.at(name))
    means = tercile_means(sweep.at(name))
    evidence = (f"highest block mean in K {best[0]}, C {best[1]} ({np.nanmax(means):.3g}); "
                if best else "the grid is too small for terciles (needs 3 x 3); ")
    evidence += _where_max(sweep, name)
    ok = best == want
    return Verdict(key, claim, ok, evidence, "" if ok else _tercile_reason(best, want))


def _tercile_reason(best: tuple[str, str] | None, want: tuple[str, str]) -> str:
    """Why a ratio peaks elsewhere, from where it peaks (the ratios are ind/post, so they grow
    where the free response after release is weakest against the forced one)."""
    if best is None:
        return "the grid is too small for terciles"
    parts = []
    if best[1] != want[1]:
        parts.append("it keeps growing with damping up to the grid's edge: heavier damping "
                     "cuts the free ringing after release (the ratio's denominator) more "
                     "than the forced response, with no turn-over at intermediate damping "
                     "within a decade of the default" if best[1] == "high" else
                     f"it is largest at {best[1]} damping")
    if best[0] != want[0]:
        parts.append(f"along the stiffness it peaks at {best[0]} K, not {want[0]} K")
    return "; ".join(parts)


def extreme_counts(shape: tuple[int, ...]) -> tuple[int, int]:
    """2A: how many of the lowest damping and of the highest stiffness values of a
    (n_K, n_C) grid are 'extreme'."""
    return (max(1, math.ceil(EXTREME_FRACTION * shape[1])),
            max(1, math.ceil(EXTREME_FRACTION * shape[0])))


def area_flat_except_extremes(sweep: SweepResult) -> Verdict:
    """2A: the area between the curves varies little over the K x C grid except at extremely
    low damping or extremely high stiffness (see the thresholds above)."""
    claim = "the area varies little except at extremely low damping or high stiffness"
    v = sweep.at("area")
    n_k = v.shape[0]
    n_low_c, n_high_k = extreme_counts(v.shape)
    extreme = np.zeros(v.shape, dtype=bool)
    extreme[:, :n_low_c] = True
    extreme[n_k - n_high_k:, :] = True
    inner, whole = v[~extreme & np.isfinite(v)], v[np.isfinite(v)]
    if inner.size == 0 or whole.size < 2:
        return Verdict("2A", claim, False, "the grid is too small to have points outside "
                       "the extremes", "grid too small")
    whole_range = float(np.ptp(whole))
    inner_range = float(np.ptp(inner))
    share = inner_range / whole_range if whole_range > 0 else math.nan
    ok = bool(whole_range > 0 and share <= AREA_ELSEWHERE_MAX_SHARE)
    dev = np.where(np.isfinite(v), np.abs(v - np.nanmedian(v)), -np.inf)
    i, j = np.unravel_index(int(np.argmax(dev)), v.shape)
    evidence = (f"range {whole_range:.3g} over the grid, {inner_range:.3g} outside the lowest "
                f"{n_low_c} damping and highest {n_high_k} stiffness values (share "
                f"{share:.2f}); largest deviation from the median ({np.nanmedian(v):.3g}) "
                f"{v[i, j]:.3g} at K {sweep.spec.stiffness_n_per_m[i]:.3g}, C "
                f"{sweep.spec.damping_n_s_per_m[j]:.3g}")
    reason = "" if ok else ("the area changes away from the extremes too: the free ringing "
                            "after release, which shapes the post-indentation curve, depends on "
                            "K and C across the whole grid, not only where it is underdamped")
    return Verdict("2A", claim, ok, evidence, reason)


def npc_ratio_region(sweep: SweepResult) -> Verdict:
    """2B: the nPC ratio is highest at intermediate damping and high compliance (low K)."""
    return _tercile_claim(
        sweep, "npc_ratio", "2B", "the nPC ratio is highest at intermediate damping and high "
        "compliance (low K)", ("low", "mid"))


def sir_ratio_region(sweep: SweepResult) -> Verdict:
    """2C: the signal-information ratio is highest at low compliance (high K) and
    intermediate damping."""
    return _tercile_claim(
        sweep, "sir_ratio", "2C", "the signal-information ratio is highest at low compliance "
        "(high K) and intermediate damping", ("high", "mid"))


WEAK_LOAD_RATIO = 0.25
"""3F's reason: input 2 'barely loads' M15's springs if its RMS force there is below this
fraction of input 3's."""


def inputs_2_3_most_similar(similarity: np.ndarray, names: Sequence[str],
                            rms_n: Sequence[float] | None = None) -> Verdict:
    """3F: inputs 2 and 3 (same push, same mass, different angle) are the most similar pair
    of distinct inputs (strictly: a tie is not a reproduction). ``rms_n``: each input's RMS
    force (N) at the sensors compared, for the evidence and the reason."""
    claim = "inputs 2 and 3 are the most similar pair"
    n = similarity.shape[0]
    pairs = [(similarity[i, j], i, j) for i in range(n) for j in range(i + 1, n)
             if np.isfinite(similarity[i, j])]
    pairs.sort(reverse=True)
    if not pairs:
        return Verdict("3F", claim, False, "no defined similarity", "every input is silent")
    top = pairs[0][0]
    ties = [(i, j) for v, i, j in pairs if v == top]
    ok = ties == [(1, 2)]
    label = {i: f"{i + 1} ({names[i]})" for i in range(n)}
    evidence = (f"index of inputs 2-3 {similarity[1, 2]:.3f}; highest {top:.3f} for "
                f"{', '.join(f'{label[i]}-{label[j]}' for i, j in ties)}; next "
                + ", ".join(f"{label[i]}-{label[j]} {v:.3f}" for v, i, j in pairs[1:3]))
    weak = False
    if rms_n is not None:
        ratio = rms_n[1] / rms_n[2] if rms_n[2] > 0 else math.nan
        weak = bool(ratio < WEAK_LOAD_RATIO)
        evidence += f"; RMS force at the sensors, input 2 / input 3: {ratio:.2f}"
    reason = ""
    if not ok:
        reason = ("input 2, the perpendicular push, barely loads M15's springs: without "
                  "large-deformation coupling a normal push hardly stretches the in-plane "
                  "springs, so input 3's response there is mostly its tangential part"
                  if weak else "another pair of inputs loads M15's springs in a more similar "
                  "pattern than the tilt of one push changes it")
    return Verdict("3F", claim, ok, evidence, reason)


def _band(acc: float) -> str:
    if acc > WELL_BELOW_FULL:
        return "above the band"
    if acc < WELL_ABOVE_CHANCE * CHANCE:
        return "below the band"
    return "in the band"


def decoding_at_operating_point(snr_db: float, decoding: dict[str, CVResult], paper_set: str
                                ) -> Verdict:
    """4F: at the paper's operating point one sensor decodes the 9 conditions well below
    100 % and well above chance. ``decoding`` maps feature set name → result at ``snr_db``;
    the verdict is the paper's set's, the evidence names every set's band."""
    claim = (f"at {snr_db:g} dB one sensor decodes well below 100 % and well above chance "
             "(1/9)")
    acc = decoding[paper_set].accuracy
    ok = _band(acc) == "in the band"
    evidence = (f"band {WELL_ABOVE_CHANCE * CHANCE:.2f}..{WELL_BELOW_FULL:.2f}: "
                + "; ".join(f"{name} {cv.accuracy:.2f} ({_band(cv.accuracy)})"
                            for name, cv in decoding.items()))
    reason = "" if ok else (
        "the sensor's spikes carry nearly all of the direction even at this noise level"
        if acc > WELL_BELOW_FULL else
        "the sensor fires only when stretched: the conditions that compress it are silent "
        "and confused with each other")
    return Verdict("4F", claim, ok, evidence, reason)


def _rising(snrs: Sequence[float], results: Sequence[CVResult]) -> tuple[bool, float]:
    acc = np.array([r.accuracy for r in results])
    rank_x = np.array([s if math.isfinite(s) else 1e9 for s in snrs])
    rho = float(spearmanr(rank_x, acc).statistic) if np.ptp(acc) > 0 else math.nan
    return bool(rho > RISING_MIN_RHO and acc[np.argmax(rank_x)] > acc[np.argmin(rank_x)]), rho


def decoding_rises_with_snr(snrs: Sequence[float], decoding: dict[str, list[CVResult]],
                            paper_set: str) -> Verdict:
    """4G: accuracy rises with the SNR (the paper's set decides; every set is shown)."""
    claim = "decoding accuracy rises with the SNR"
    parts = []
    for name, results in decoding.items():
        rising, rho = _rising(snrs, results)
        parts.append(f"{name}: {' → '.join(f'{r.accuracy:.2f}' for r in results)} "
                     f"(rho {rho:.2f}{', rising' if rising else ''})")
    ok, _ = _rising(snrs, decoding[paper_set])
    evidence = f"over {', '.join(f'{s:g}' for s in snrs)} dB: " + "; ".join(parts)
    reason = "" if ok else ("accuracy is flat: the sensor fires only when stretched, so the "
                            "conditions that compress it stay silent and cannot be told apart "
                            "at any SNR, and over this SNR range the noise changes few of the "
                            "evoked spikes")
    return Verdict("4G", claim, ok, evidence, reason)
