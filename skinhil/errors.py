"""The exceptions of skinhil: the one exceptions module, :mod:`protocols.errors`, re-exported
here so ``from skinhil.errors import ConfigError`` reads as the rest of skinhil does."""

from __future__ import annotations

from protocols.errors import (
    ConfigError,
    ModelFileError,
    ProtocolError,
    SkinhilError,
    TransportError,
)

__all__ = ["ConfigError", "ModelFileError", "ProtocolError", "SkinhilError", "TransportError"]
