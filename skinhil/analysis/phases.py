"""The two phases of a touch, as windows of a simulated response.

For a stimulus with onset at ``onset_s`` and indentation lasting ``indentation_s`` (paper
Figure 1D), the **indentation phase** is ``[onset, onset + indentation)`` and the
**post-indentation phase** the same length right after it, ``[end, end + indentation)``
(defaults: 0–0.25 s and 0.25–0.5 s, so a 0.5 s simulation holds both). A window is the steps
``k`` with ``start ≤ k·dt < stop``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.stimuli import Stimulus
from skinhil.validation import Constraints, Predicate, validate_params


def _is_window(value: tuple[float, float]) -> bool:
    lo, hi = value
    return math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi


_WINDOW = Predicate(_is_window, "(start, stop) seconds with 0 <= start < stop, both finite")


@dataclass(frozen=True)
class PhaseWindows:
    """Indentation and post-indentation windows (s, from t = 0 of the simulation)."""

    indentation_s: tuple[float, float] = (0.0, 0.25)
    post_s: tuple[float, float] = (0.25, 0.5)

    _parameter_constraints: ClassVar[Constraints] = {
        "indentation_s": _WINDOW,
        "post_s": _WINDOW,
    }

    def __post_init__(self) -> None:
        validate_params(self)

    @classmethod
    def of(cls, stimuli: Sequence[Stimulus]) -> PhaseWindows:
        """The windows of stimuli that share one onset and indentation length."""
        onsets = {s.onset_s for s in stimuli}
        lengths = {s.indentation_s for s in stimuli}
        if len(onsets) != 1 or len(lengths) != 1:
            raise ConfigError("phase windows need stimuli with one common onset_s and "
                              "indentation_s; give PhaseWindows explicitly")
        on, length = onsets.pop(), lengths.pop()
        return cls((on, on + length), (on + length, on + 2 * length))

    @property
    def duration_s(self) -> float:
        """Simulation length (s) that holds both windows."""
        return max(self.indentation_s[1], self.post_s[1])

    def steps(self, dt_s: float) -> tuple[slice, slice]:
        """Step slices of the two windows at step ``dt_s`` (s)."""
        def cut(lo: float, hi: float) -> slice:
            return slice(int(math.ceil(lo / dt_s - 1e-9)), int(math.ceil(hi / dt_s - 1e-9)))
        return cut(*self.indentation_s), cut(*self.post_s)


def phase_samples(responses: np.ndarray, window: slice) -> np.ndarray:
    """Responses (n_stim, n_steps, n_features) → PCA data matrix (n_stim·n_window, n_features):
    the window's steps of every stimulus, stacked stimulus by stimulus."""
    r = np.asarray(responses)
    if r.ndim != 3:
        raise ConfigError(f"responses must be (n_stimuli, n_steps, n_features), got {r.shape}")
    part = r[:, window]
    if part.shape[1] < 1:
        raise ConfigError(f"the phase window {window} lies outside the {r.shape[1]} simulated "
                          "steps; simulate longer")
    return np.asarray(part.reshape(-1, r.shape[2]))

