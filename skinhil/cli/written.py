"""The one line a command prints on stderr for each file it wrote (``serve --score``,
``--truth``, ``--record``, ``listen --record``, ...): the user learns where, stdout stays the
command's results (its JSON lines with ``--json``)."""

from __future__ import annotations

import sys
from pathlib import Path


def say_written(command: str, what: str, path: Path, quiet: bool = False) -> None:
    """``skinhil COMMAND: wrote WHAT to PATH`` on stderr (the absolute path), unless
    ``quiet``."""
    if not quiet:
        print(f"skinhil {command}: wrote {what} to {path.resolve()}", file=sys.stderr,
              flush=True)
