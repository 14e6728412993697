"""The generators' shared pieces: trial onsets with jittered intervals, places over the
skin's inner area, values over a range (SI units)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skinhil.model.geometry import MeshSize


def inner_half_extent_m(size: MeshSize, spacing_m: float) -> tuple[float, float]:
    """Half the width and height (m) of the skin's inner area: the square spanned by the free
    masses of the top layer (all but its edge), centred on the skin's centre."""
    rows, cols = size
    return (cols - 3) / 2 * spacing_m, (rows - 3) / 2 * spacing_m


def places_m(rng: np.random.Generator, n: int, size: MeshSize, spacing_m: float
             ) -> np.ndarray:
    """``n`` places (x, y) m drawn uniformly over the skin's inner area."""
    hx, hy = inner_half_extent_m(size, spacing_m)
    return rng.uniform((-hx, -hy), (hx, hy), size=(n, 2))


def uniform(rng: np.random.Generator, n: int, lo: float, hi: float) -> np.ndarray:
    """``n`` values drawn uniformly in ``lo``..``hi``."""
    return rng.uniform(lo, hi, size=n)


def log_uniform(rng: np.random.Generator, n: int, lo: float, hi: float) -> np.ndarray:
    """``n`` values whose logarithms are drawn uniformly in log ``lo``..log ``hi`` (> 0)."""
    return np.exp(rng.uniform(np.log(lo), np.log(hi), size=n))


def choices(rng: np.random.Generator, n: int, classes: Sequence[float]) -> np.ndarray:
    """``n`` values drawn uniformly from ``classes``."""
    return np.asarray(classes, dtype=float)[rng.integers(0, len(classes), size=n)]


def onsets_s(rng: np.random.Generator, lasts_s: Sequence[float], lead_s: tuple[float, float],
             gap_s: tuple[float, float]) -> np.ndarray:
    """Start times (s) of trials lasting ``lasts_s`` each: the first after a lead drawn in
    ``lead_s``, each next one a gap drawn in ``gap_s`` after the previous has ended (so the
    interval between onsets is jittered and no two trials overlap)."""
    gaps = rng.uniform(*gap_s, size=len(lasts_s))
    starts = np.empty(len(lasts_s))
    t = float(rng.uniform(*lead_s))
    for i, last in enumerate(lasts_s):
        starts[i] = t
        t += float(last) + float(gaps[i])
    return starts
