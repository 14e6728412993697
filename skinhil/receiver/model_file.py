"""Loading a saved direction decoder for the receiver (refusing what does not fit)."""

from __future__ import annotations

from pathlib import Path

from skinhil.decoding import DirectionDecoder
from skinhil.receiver.decoder_adapter import WindowDecoder


def load_window_decoder(path: str | Path, n_channels: int | None = None) -> WindowDecoder:
    """Load a decoder file written by ``skinhil train`` (for a stream of ``n_channels``
    channels, when given).

    Raises :class:`skinhil.errors.ModelFileError` for a missing, corrupted, pickled or
    mismatched file (the decoding package's loader checks it).
    """
    return WindowDecoder(DirectionDecoder.load(path, n_channels=n_channels))
