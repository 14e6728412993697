"""The three information measures of a response set (paper Figures 1E-F and 2).

:func:`information_measures` takes the sensor responses of a set of stimuli
(n_stimuli, n_steps, n_features) sampled every ``dt_s`` and the phase windows, runs the PCA of
:mod:`skinhil.analysis.pca` on each phase (data matrix of :func:`phase_samples`) and returns
the area between the variance-explained curves (the paper's sign), the nPC99 of each phase
and their ratio, and the signal-information ratio of each phase and their ratio (the
project's reading and the literal eq. 10 one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinhil.analysis.pca import PhasePCA, area_between, phase_pca
from skinhil.analysis.phases import PhaseWindows, phase_samples


@dataclass(frozen=True)
class InformationMeasures:
    """Measures of one response set (see :mod:`skinhil.analysis.pca` for definitions)."""

    area: float
    npc99_ind: float
    npc99_post: float
    npc_ratio: float
    sir_ind: float
    sir_post: float
    sir_ratio: float
    sir_literal_ind: float = math.nan
    sir_literal_post: float = math.nan
    sir_literal_ratio: float = math.nan
    """The literal eq. 10 SIR of each phase and their ratio (:mod:`skinhil.analysis.pca`)."""

    def as_dict(self) -> dict[str, float]:
        """Plain ``{name: value}``."""
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


def _ratio(a: float, b: float) -> float:
    if math.isnan(a) or math.isnan(b) or b == 0:
        return math.nan
    return a / b


def phase_pcas(responses: np.ndarray, dt_s: float,
               windows: PhaseWindows | None = None) -> tuple[PhasePCA, PhasePCA]:
    """PCA of the indentation and of the post-indentation phase."""
    w = windows or PhaseWindows()
    ind, post = w.steps(dt_s)
    return phase_pca(phase_samples(responses, ind)), phase_pca(phase_samples(responses, post))


def measures_from_pcas(ind: PhasePCA, post: PhasePCA) -> InformationMeasures:
    """The measures from the two phases' PCAs."""
    area = area_between(ind.curve, post.curve)
    return InformationMeasures(area=area, npc99_ind=ind.npc99, npc99_post=post.npc99,
                               npc_ratio=_ratio(ind.npc99, post.npc99), sir_ind=ind.sir,
                               sir_post=post.sir, sir_ratio=_ratio(ind.sir, post.sir),
                               sir_literal_ind=ind.sir_literal,
                               sir_literal_post=post.sir_literal,
                               sir_literal_ratio=_ratio(ind.sir_literal, post.sir_literal))


def information_measures(responses: np.ndarray, dt_s: float,
                         windows: PhaseWindows | None = None) -> InformationMeasures:
    """Measures of responses (n_stimuli, n_steps, n_features) sampled every ``dt_s`` (s)."""
    return measures_from_pcas(*phase_pcas(responses, dt_s, windows))
