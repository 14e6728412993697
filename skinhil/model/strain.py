"""The skin's strain: how far its springs stretch or shorten relative to their rest length.

A spring's sensor signal under the length readout is ``k·(L − L0)`` (N), so its strain is
``|signal| / (k·L0)``; under the axial readout the same ratio is the axial strain (its
small-displacement limit). A plausible skin stays within tens of percent.
"""

from __future__ import annotations

import numpy as np

from skinhil.model.skin import SkinModel


def rest_lengths_m(model: SkinModel) -> np.ndarray:
    """Each spring's rest length (m), in sensor order."""
    d = model.positions[model.springs[:, 1]] - model.positions[model.springs[:, 0]]
    return np.linalg.norm(d, axis=1)


def max_strain(spring_forces_n: np.ndarray, model: SkinModel) -> float:
    """Largest strain (a fraction: 0.2 is 20 %) of any spring in ``spring_forces_n``
    ((n_steps, n_springs) N, the model's sensor signals); 0 for no steps."""
    if spring_forces_n.size == 0:
        return 0.0
    peak = np.abs(spring_forces_n).max(axis=0)
    return float(np.max(peak / (model.params.stiffness_n_per_m * rest_lengths_m(model))))
