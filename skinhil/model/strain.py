"""The skin's strain: how far its springs stretch or shorten relative to their rest length.

A spring's sensor signal under the length readout is ``k·(L − L0)`` (N), so its strain is
``|signal| / (k·L0)``; under the axial readout the same ratio is the axial strain (its
small-displacement limit). A plausible skin stays within tens of percent.

Summary of a set of runs (:func:`strain_summary`, what REPORT.md puts beside every verdict):
the **max** is the largest strain of any spring at any time in any run; the **median** is the
median, over every run's springs, of each spring's peak strain in that run (how far the
typical spring is taken).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from skinhil.model.geometry import MeshSize, build_mesh
from skinhil.model.skin import SkinModel, SkinParams


def rest_lengths_m(model: SkinModel) -> np.ndarray:
    """Each spring's rest length (m), in sensor order."""
    d = model.positions[model.springs[:, 1]] - model.positions[model.springs[:, 0]]
    return np.linalg.norm(d, axis=1)


@functools.lru_cache(maxsize=16)
def _rest_lengths(spacing_m: float, layer_gap_m: float, size: MeshSize) -> np.ndarray:
    mesh = build_mesh(spacing_m, layer_gap_m, size)
    d = mesh.positions[mesh.springs[:, 1]] - mesh.positions[mesh.springs[:, 0]]
    return np.linalg.norm(d, axis=1)


def rest_lengths_of(params: SkinParams) -> np.ndarray:
    """Rest lengths (m) of the springs of a skin with ``params``, without building its model."""
    return _rest_lengths(params.spacing_m, params.layer_gap_m, params.size)


def max_strain(spring_forces_n: np.ndarray, model: SkinModel) -> float:
    """Largest strain (a fraction: 0.2 is 20 %) of any spring in ``spring_forces_n``
    ((n_steps, n_springs) N, the model's sensor signals); 0 for no steps."""
    if spring_forces_n.size == 0:
        return 0.0
    peak = np.abs(spring_forces_n).max(axis=0)
    return float(np.max(peak / (model.params.stiffness_n_per_m * rest_lengths_m(model))))


@dataclass(frozen=True)
class StrainSummary:
    """Strain of a set of runs (fractions: 0.2 is 20 %; module docstring)."""

    max: float
    median: float

    def text(self) -> str:
        """``"strain max 150 %, median 12 %"``."""
        return f"strain max {self.max:.3g}, median {self.median:.3g}"

    @staticmethod
    def combine(parts: list[StrainSummary]) -> StrainSummary:
        """Several sets' summaries as one: the largest max, the median of the medians."""
        finite = [p for p in parts if np.isfinite(p.max)]
        if not finite:
            return StrainSummary(float("nan"), float("nan"))
        return StrainSummary(max(p.max for p in finite),
                             float(np.median([p.median for p in finite])))


def strain_summary(spring_forces_n: np.ndarray, params: SkinParams) -> StrainSummary:
    """Summary of runs ``spring_forces_n`` ((n_runs, n_steps, n_springs) or (n_steps,
    n_springs), N: the sensor signals of a skin with ``params``)."""
    f = np.asarray(spring_forces_n, dtype=float)
    if f.ndim == 2:
        f = f[None]
    if f.size == 0:
        return StrainSummary(0.0, 0.0)
    peak = np.abs(f).max(axis=1)  # (n_runs, n_springs)
    strain = peak / (params.stiffness_n_per_m * rest_lengths_of(params))
    return StrainSummary(float(strain.max()), float(np.median(strain)))
