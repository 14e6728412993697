"""A trained :class:`skinhil.decoding.DirectionDecoder` seen as a decision on one PSP window.

The receiver owns no feature or classifier code: it hands the decoder's own feature
definition the PSP values (n_steps, n_channels) of the window that starts at the detected
onset, exactly as training handed it the window that starts at the true onset, and asks the
decoder for its decision values.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skinhil.model.psp import PSPParams


class WindowDecoder:
    """Decision on one PSP window by a trained direction decoder (no copy of its logic)."""

    def __init__(self, decoder: Any) -> None:
        self.decoder = decoder
        spec = decoder.spec_
        self.spec = spec
        self.dt_s = float(spec.dt_s)
        self.n_channels = int(spec.n_channels)
        self.psp_params: PSPParams = spec.psp
        self.window_steps = int(spec.n_steps)
        self.classes = np.asarray(decoder.classes_)

    def decide(self, window_psp: np.ndarray) -> tuple[int, np.ndarray]:
        """PSP window (window_steps, n_channels) → (predicted class, decision values)."""
        x = self.spec.transform(window_psp[None])
        scores = np.asarray(self.decoder.decision_function(x))[0]
        return int(self.classes[int(np.argmax(scores))]), scores
