"""Where the demo caches what it fits on first use (its decoder, the grip readout)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/skinhil`` or ``~/.cache/skinhil``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "skinhil"
