"""Loading a saved direction decoder for the receiver (refusing what does not fit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skinhil.decoding import DirectionDecoder
from skinhil.errors import ModelFileError
from skinhil.receiver.decoder_adapter import WindowDecoder


def load_window_decoder(path: str | Path, n_channels: int | None = None) -> WindowDecoder:
    """Load a decoder file written by ``skinhil train`` (for a stream of ``n_channels``
    channels, when given).

    Raises :class:`skinhil.errors.ModelFileError` for a missing, corrupted, pickled or
    mismatched file (the decoding package's loader checks it), and for a decoder whose class
    labels are not stimulus ids (integers 0..2^24-1: what the receiver decides and the board
    scores, SPEC.md §3.5.1).
    """
    decoder = DirectionDecoder.load(path, n_channels=n_channels)
    classes = np.asarray(decoder.classes_)
    if classes.dtype.kind not in "iu" or not np.all((classes >= 0) & (classes < 1 << 24)):
        raise ModelFileError(f"decoder file '{path}' has class labels that are not stimulus "
                             "ids (integers 0..16777215) — train it with 'skinhil train'")
    return WindowDecoder(decoder)
