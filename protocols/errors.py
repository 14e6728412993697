"""The one exceptions module of protocols, firmware_sim and skinhil (which re-exports it as
``skinhil.errors``): the wire codecs stand alone, so the errors live with them.

Every error raised on bad input is a :class:`SkinhilError`; its message says what was wrong
and what to do, in one line, so the CLI can print it as it is.
"""

from __future__ import annotations


class SkinhilError(Exception):
    """Base of every error this project raises on purpose."""


class ConfigError(SkinhilError, ValueError):
    """A parameter, stimulus, schedule or configuration file is invalid."""


class ProtocolError(SkinhilError, ValueError):
    """Data cannot be encoded in (or is not) the documented wire format."""


class TransportError(SkinhilError, OSError):
    """A serial port or CAN bus cannot be opened or has gone away."""


class ModelFileError(SkinhilError, ValueError):
    """A saved decoder model is missing, corrupted, not plain data, or does not match."""
