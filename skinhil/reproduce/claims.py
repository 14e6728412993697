"""The paper's claims, checked against computed numbers with thresholds fixed in advance.

Each check returns a :class:`Verdict`: whether the numbers support the claim, what they are,
and, when they do not, which part of the rule failed (the report names the likely cause from
the run's own experiment: the same dynamics with the other readout, the other dynamics with
the same readout). The thresholds (named constants below) and the rules were written before
any result of the run they judge, and are the same for every mechanics and readout. One row
of REPORT.md per claim, mechanics and readout: 1E-F, 2A, 2B, 2C, 3F, 4F, 4G. Every rule has a
test on made-up numbers that must pass and one that must fail (tests/test_reproduce.py).

2B and 2C ("highest at intermediate damping", at high or low compliance) are read as the
paper states them, with nothing decided by a tie order or by where the grid ends: each
measure (the nPC ratio for 2B, the SIR ratio for 2C) must **turn over in damping** (its
profile along C, averaged over K, has both ends at least :data:`TURNOVER_MIN_DROP` below its
largest value: values, not indices), and the two optima must lie **relative to each other**
as stated: the nPC ratio's at lower K (higher compliance) than the SIR ratio's, by at least
:data:`MIN_SEPARATION_DECADES` (an optimum is the centroid of the map's top region,
:func:`optimum_location`, a set of points, not one index). Before the check, the run
extends the damping grid past any end the profile peaks at (:func:`edge_of_optimum`,
:mod:`skinhil.reproduce.compute`), so a grid is as wide as the measure needs to turn over
(within the extensions allowed). The tercile reading (:func:`damping_optimum`, the peak's K
tercile) is for the figures only.

3F is judged on the per-sensor mean correlation, as the paper computes it
(:func:`skinhil.analysis.correlation.similarity_matrix_per_sensor`); the pooled index is
shown beside it.
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

EXTREME_FRACTION = 0.2
"""2A: 'extremely low damping' is the lowest 20 % of the damping grid values (at least
one), 'extremely high stiffness' the highest 20 % of the stiffness values."""
AREA_ELSEWHERE_MAX_SHARE = 0.25
"""2A: the area 'varies little' elsewhere if the 90th percentile of its distance from the
median away from the extremes is at most this fraction of the largest distance at them."""
TIE_RTOL = 1e-9
"""2B/2C: values of a profile within this fraction of its largest tie for the largest."""
TURNOVER_MIN_DROP = 0.02
"""2B/2C: an interior peak counts as an optimum if both ends of the damping profile are at
least this fraction of the peak's size below it."""
RESPONSE_FLOOR_SPIKES = 1.0
"""4F: the paper's sensor responds to every condition (its Fig 4B, 4E): at least this many
spikes per trial, on average, in each of the 9 conditions at the operating point (over the
trial of the rasters, 0.3 s; the neuron is silent at rest)."""
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


def information_phases(m: InformationMeasures,
                       stacked: InformationMeasures | None = None) -> Verdict:
    """1E-F, as the paper states it, on stimulus 1 (its Figure 1's normal press on M15): the
    indentation phase spreads its variance over more components than the post-indentation
    phase (nPC99 ratio above 1) and the indentation curve lies below the post-indentation
    one (the area between them, the paper's sign, negative). ``stacked``: the same measures
    of the five inputs stacked (shown, not judged)."""
    claim = "more information during indentation than after it"
    ok = m.npc_ratio > 1 and m.area < 0
    evidence = (f"stimulus 1: nPC99 indentation {m.npc99_ind:g} vs post {m.npc99_post:g} "
                f"(ratio {m.npc_ratio:.3g}); area between curves {m.area:.3g}; SIR ind "
                f"{m.sir_ind:.3g} vs post {m.sir_post:.3g} (literal eq. 10: "
                f"{m.sir_literal_ind:.3g} vs {m.sir_literal_post:.3g})")
    if stacked is not None:
        evidence += (f"; the 5 inputs stacked (extra): nPC99 {stacked.npc99_ind:g} vs "
                     f"{stacked.npc99_post:g}, area {stacked.area:.3g}")
    failed = []
    if math.isnan(m.npc_ratio):
        failed.append("a phase has no variance at all (silent): the measures are undefined")
    else:
        if not m.npc_ratio > 1:
            failed.append("the post-indentation phase needs as many or more components")
        if not m.area < 0:
            failed.append("the indentation curve does not lie below the post-indentation one")
    return Verdict("1E-F", claim, ok, evidence, "; ".join(failed))


def tercile_groups(n: int) -> list[np.ndarray]:
    """Grid indices 0..n-1 split into the low, mid and high terciles (empty if n < 3)."""
    return [np.asarray(g, dtype=np.int64) for g in np.array_split(np.arange(n), 3)]


def tercile_means(values: np.ndarray) -> np.ndarray:
    """(3, 3) mean of a (n_K, n_C) map per (K tercile, C tercile) block (NaN: empty block or
    no finite value); shown in the report, no claim depends on it."""
    v = np.asarray(values, dtype=float)
    out = np.full((3, 3), np.nan)
    for i, gk in enumerate(tercile_groups(v.shape[0])):
        for j, gc in enumerate(tercile_groups(v.shape[1])):
            block = v[np.ix_(gk, gc)]
            if np.isfinite(block).any():
                out[i, j] = float(np.nanmean(block))
    return out


def peak_index(profile: np.ndarray) -> int | None:
    """Index of the largest value of a 1-D profile, ties broken explicitly: every value within
    :data:`TIE_RTOL` (relative) of the largest ties, and the middle one of the tied indices
    wins (the lower of the two middle ones for an even count). None if nothing is finite."""
    p = np.asarray(profile, dtype=float)
    if not np.isfinite(p).any():
        return None
    top = float(np.nanmax(p))
    tied = np.flatnonzero(np.isfinite(p) & (p >= top - TIE_RTOL * abs(top)))
    return int(tied[(tied.size - 1) // 2])


def damping_profile(values: np.ndarray) -> np.ndarray:
    """A (n_K, n_C) measure averaged over K (finite values): its profile along damping."""
    v = np.asarray(values, dtype=float)
    out = np.full(v.shape[1], np.nan)
    for j in range(v.shape[1]):
        col = v[:, j][np.isfinite(v[:, j])]
        if col.size:
            out[j] = float(col.mean())
    return out


def edge_of_optimum(values: np.ndarray) -> str | None:
    """"low" or "high" when the K-averaged measure peaks at that end of the damping grid (so
    the grid should be extended there before 2B/2C are judged), else None."""
    j = peak_index(damping_profile(values))
    if j is None:
        return None
    n = np.asarray(values).shape[1]
    return "low" if j == 0 else "high" if j == n - 1 else None


@dataclass(frozen=True)
class DampingOptimum:
    """Where a measure peaks in damping (the K-averaged profile) and, at that damping, in K."""

    interior: bool
    """The peak is not at either end of the damping grid and both ends are lower than it by
    at least :data:`TURNOVER_MIN_DROP` of its size: the measure turns over."""
    c_index: int
    k_index: int
    drops: tuple[float, float]
    """How much lower the low-C and the high-C ends of the profile are, relative to the peak."""


def damping_optimum(values: np.ndarray) -> DampingOptimum | None:
    """2B/2C's rule on a (n_K, n_C) map (module docstring); None without a finite value."""
    v = np.asarray(values, dtype=float)
    profile = damping_profile(v)
    j = peak_index(profile)
    if j is None:
        return None
    i = peak_index(v[:, j])
    assert i is not None  # column j has a finite value, or its mean would be NaN
    top = profile[j]
    ends = [profile[np.flatnonzero(np.isfinite(profile))[k]] for k in (0, -1)]
    scale = abs(top) if top != 0 else 1.0
    drops = (float((top - ends[0]) / scale), float((top - ends[1]) / scale))
    interior = 0 < j < v.shape[1] - 1 and min(drops) >= TURNOVER_MIN_DROP
    return DampingOptimum(bool(interior), j, i, drops)


def turnover(values: np.ndarray) -> tuple[float, float]:
    """2B/2C: how far below the largest value of the K-averaged damping profile of a
    (n_K, n_C) map its low-C and high-C ends lie, relative to that value (NaN, NaN without a
    finite value). Values, not indices: no tie order enters."""
    profile = damping_profile(values)
    finite = profile[np.isfinite(profile)]
    if finite.size == 0:
        return math.nan, math.nan
    top = float(finite.max())
    scale = abs(top) if top != 0 else 1.0
    return float((top - finite[0]) / scale), float((top - finite[-1]) / scale)


def optimum_location(values: np.ndarray, stiffness: Sequence[float],
                     damping: Sequence[float]) -> tuple[float, float] | None:
    """Where a (n_K, n_C) map is highest: the centroid, in log10 K and log10 C, of its top
    region (the points at or above the :data:`OPTIMUM_TOP_QUANTILE` quantile of its finite
    values). A set, not an index: ties all count, none by its place in the grid. None
    without a finite value."""
    v = np.asarray(values, dtype=float)
    finite = np.isfinite(v)
    if not finite.any():
        return None
    cut = float(np.quantile(v[finite], OPTIMUM_TOP_QUANTILE))
    i, j = np.nonzero(finite & (v >= cut))
    return (float(np.mean(np.log10(np.asarray(stiffness))[i])),
            float(np.mean(np.log10(np.asarray(damping))[j])))


OPTIMUM_TOP_QUANTILE = 0.9
"""2B/2C: a map's optimum is the centroid of its top 10 % of points."""
MIN_SEPARATION_DECADES = 0.1
"""2B/2C: one optimum lies at lower K than the other if their log10 K differ by at least
this (a tenth of a decade, about a third of the full grid's step)."""


def _optimum_claim(sweep: SweepResult, name: str, other: str, key: str, claim: str,
                   lower: bool) -> Verdict:
    """2B/2C (module docstring): ``name`` turns over in damping (an intermediate optimum)
    and its optimum lies at lower (``lower``) or higher K than ``other``'s."""
    v = sweep.at(name)
    ks, cs = sweep.spec.stiffness_n_per_m, sweep.spec.damping_n_s_per_m
    grid = (f"grid K {ks[0]:.3g}..{ks[-1]:.3g} N/m x C {cs[0]:.3g}..{cs[-1]:.3g} N·s/m "
            f"({len(ks)} x {len(cs)})")
    here, there = optimum_location(v, ks, cs), optimum_location(sweep.at(other), ks, cs)
    if here is None or there is None:
        return Verdict(key, claim, False, f"no finite value; {grid}", "no finite value")
    drops = turnover(v)
    turns = min(drops) >= TURNOVER_MIN_DROP
    gap = here[0] - there[0]
    side = "lower" if lower else "higher"
    placed = gap <= -MIN_SEPARATION_DECADES if lower else gap >= MIN_SEPARATION_DECADES
    evidence = (f"optimum (centroid of the top {1 - OPTIMUM_TOP_QUANTILE:.0%}) of {name} at K "
                f"{10 ** here[0]:.3g} N/m, C {10 ** here[1]:.3g} N·s/m; of {other} at K "
                f"{10 ** there[0]:.3g}, C {10 ** there[1]:.3g} ({gap:+.2f} decades in K); "
                f"K-averaged profile in C: ends below its top by {drops[0]:.1%} (low C) and "
                f"{drops[1]:.1%} (high C); {grid}")
    failed = []
    if not turns:
        failed.append("no intermediate optimum in damping: the profile does not turn over "
                      f"within the grid (an end within {TURNOVER_MIN_DROP:.0%} of its top)")
    if not placed:
        failed.append(f"its optimum does not lie at {side} K than the {other}'s")
    return Verdict(key, claim, bool(turns and placed), evidence, "; ".join(failed))


def extreme_counts(shape: tuple[int, ...]) -> tuple[int, int]:
    """2A: how many of the lowest damping and of the highest stiffness values of a
    (n_K, n_C) grid are 'extreme'."""
    return (max(1, math.ceil(EXTREME_FRACTION * shape[1])),
            max(1, math.ceil(EXTREME_FRACTION * shape[0])))


def extreme_mask(shape: tuple[int, ...]) -> np.ndarray:
    """2A: the (n_K, n_C) points at extremely low damping or extremely high stiffness."""
    n_low_c, n_high_k = extreme_counts(shape)
    extreme = np.zeros(shape[:2], dtype=bool)
    extreme[:, :n_low_c] = True
    extreme[shape[0] - n_high_k:, :] = True
    return extreme


def area_flat_except_extremes(sweep: SweepResult) -> Verdict:
    """2A: the area between the curves varies little over the K x C grid except at extremely
    low damping or extremely high stiffness.

    Rule: with ``dev`` each point's distance from the median area of the points outside the
    extremes, (a) the largest ``dev`` of the grid lies at an extreme point and (b) the 90th
    percentile of ``dev`` outside the extremes is at most :data:`AREA_ELSEWHERE_MAX_SHARE` of
    that largest one. Passes: a map flat away from the extremes whose big departures sit at
    them (a resonance at low damping, stiff skins). Fails: a map that changes across the
    whole grid (e.g. an area growing steadily with log C), whatever the extremes do, and a
    map whose largest change lies away from them.
    """
    claim = "the area varies little except at extremely low damping or high stiffness"
    v = sweep.at("area")
    extreme = extreme_mask(v.shape)
    finite = np.isfinite(v)
    inner, outer = v[~extreme & finite], v[extreme & finite]
    if inner.size == 0 or outer.size == 0:
        return Verdict("2A", claim, False, "the grid is too small to have points inside and "
                       "at the extremes", "grid too small")
    centre = float(np.median(inner))
    dev_in, dev_out = np.abs(inner - centre), np.abs(outer - centre)
    biggest = float(dev_out.max())
    spread = float(np.quantile(dev_in, 0.9))
    at_extreme = biggest > float(dev_in.max())
    share = spread / biggest if biggest > 0 else math.inf
    ok = bool(at_extreme and share <= AREA_ELSEWHERE_MAX_SHARE)
    dev = np.where(finite, np.abs(v - centre), -np.inf)
    i, j = np.unravel_index(int(np.argmax(dev)), v.shape)
    n_low_c, n_high_k = extreme_counts(v.shape)
    where = "an extreme" if extreme[i, j] else "not an extreme"
    evidence = (f"median area away from the extremes {centre:.3g}; 90th percentile of the "
                f"deviation there {spread:.3g}, {share:.2f} of the largest at the extremes "
                f"({biggest:.3g}); largest deviation of the grid {v[i, j]:.3g} at K "
                f"{sweep.spec.stiffness_n_per_m[i]:.3g}, C "
                f"{sweep.spec.damping_n_s_per_m[j]:.3g} ({where}; extremes: lowest {n_low_c} C, "
                f"highest {n_high_k} K)")
    failed = []
    if not at_extreme:
        failed.append("the largest change of the area lies away from the extremes")
    if share > AREA_ELSEWHERE_MAX_SHARE:
        failed.append(f"away from the extremes it still varies by {share:.2f} of the change "
                      f"at them (rule: <= {AREA_ELSEWHERE_MAX_SHARE:.2f})")
    return Verdict("2A", claim, ok, evidence, "; ".join(failed))


def npc_ratio_region(sweep: SweepResult) -> Verdict:
    """2B: the nPC ratio is highest at intermediate damping and high compliance (low K)."""
    return _optimum_claim(
        sweep, "npc_ratio", "sir_ratio", "2B", "the nPC ratio is highest at intermediate "
        "damping and high compliance (low K)", lower=True)


def sir_ratio_region(sweep: SweepResult) -> Verdict:
    """2C: the signal-information ratio is highest at low compliance (high K) and
    intermediate damping."""
    return _optimum_claim(
        sweep, "sir_ratio", "npc_ratio", "2C", "the signal-information ratio is highest at low "
        "compliance (high K) and intermediate damping", lower=False)


WEAK_LOAD_RATIO = 0.25
"""3F's reason: input 2 'barely loads' M15's springs if its RMS force there is below this
fraction of input 3's."""


def inputs_2_3_most_similar(similarity: np.ndarray, names: Sequence[str],
                            rms_n: Sequence[float] | None = None,
                            pooled: np.ndarray | None = None) -> Verdict:
    """3F: inputs 2 and 3 (same push, same mass, different angle) are the most similar pair
    of distinct inputs (strictly: a tie is not a reproduction) in ``similarity`` (the
    per-sensor mean, as the paper). ``rms_n``: each input's RMS force (N) at the sensors
    compared, for the evidence and the reason; ``pooled``: the pooled index matrix, shown."""
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
    if pooled is not None:
        others = max(pooled[i, j] for _, i, j in pairs if (i, j) != (1, 2))
        evidence += (f"; pooled index (extra): inputs 2-3 {pooled[1, 2]:.3f}, highest other "
                     f"pair {others:.3f}")
    reason = ""
    if not ok:
        reason = ("inputs 2-3 tie with another pair" if len(ties) > 1 and (1, 2) in ties else
                  "another pair is more similar")
        if weak:
            reason += (f"; input 2 loads M15's sensors with under {WEAK_LOAD_RATIO:.0%} of "
                       "input 3's RMS force")
    return Verdict("3F", claim, ok, evidence, reason)


def _band(acc: float) -> str:
    if acc > WELL_BELOW_FULL:
        return "above the band"
    if acc < WELL_ABOVE_CHANCE * CHANCE:
        return "below the band"
    return "in the band"


def decoding_at_operating_point(snr_db: float, decoding: dict[str, CVResult], paper_set: str,
                                spikes_per_condition: Sequence[float] | np.ndarray) -> Verdict:
    """4F: at the paper's operating point one sensor, responding to every condition, decodes
    the 9 conditions well below 100 % and well above chance. ``decoding`` maps feature set
    name → result at ``snr_db``; the verdict is the paper's set's, the evidence names every
    set's band. ``spikes_per_condition``: the paper's sensor's mean spikes per trial in each
    condition at ``snr_db``; each must reach :data:`RESPONSE_FLOOR_SPIKES` (a sensor silent in
    some conditions can land in the band by splitting them between a few classes)."""
    claim = (f"at {snr_db:g} dB one sensor, responding to every condition, decodes well below "
             "100 % and well above chance (1/9)")
    acc = decoding[paper_set].accuracy
    counts = np.asarray(spikes_per_condition, dtype=float)
    silent = np.flatnonzero(~(counts >= RESPONSE_FLOOR_SPIKES))
    ok = _band(acc) == "in the band" and silent.size == 0
    evidence = (f"band {WELL_ABOVE_CHANCE * CHANCE:.2f}..{WELL_BELOW_FULL:.2f}: "
                + "; ".join(f"{name} {cv.accuracy:.2f} ({_band(cv.accuracy)})"
                            for name, cv in decoding.items())
                + f"; {paper_set} spikes per trial per condition "
                + "/".join(f"{c:.1f}" for c in counts)
                + f" (floor {RESPONSE_FLOOR_SPIKES:g})")
    failed = []
    if _band(acc) != "in the band":
        failed.append(f"accuracy {acc:.2f} is {_band(acc)}")
    if silent.size:
        failed.append(f"silent (below {RESPONSE_FLOOR_SPIKES:g} spike per trial) in "
                      f"{silent.size} of {counts.size} conditions "
                      f"({', '.join(str(int(c)) for c in silent)})")
    return Verdict("4F", claim, ok, evidence, "; ".join(failed))


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
    ok, rho = _rising(snrs, decoding[paper_set])
    evidence = f"over {', '.join(f'{s:g}' for s in snrs)} dB: " + "; ".join(parts)
    reason = "" if ok else (f"rank correlation {rho:.2f} (rule: above {RISING_MIN_RHO:g}, and "
                            "the noise-free accuracy above the lowest SNR's)")
    return Verdict("4G", claim, ok, evidence, reason)
