"""The cold kernel cache notice: a command about to run kernels that are not compiled yet
says so, for about how long, and where they will be cached.

The model's and the wire's kernels are compiled on first use and cached on disk
(:mod:`protocols.kernel_cache`: ``$NUMBA_CACHE_DIR`` or ``skinhil/__pycache__/numba`` next
to the sources, one directory per version of the sources). The first run after an install
or a change of the sources spends :data:`COLD_COMPILE_S` compiling before it starts;
``serve``, ``listen``, ``demo``, ``train`` and ``simulate`` call :func:`announce_cold_cache`
once their input is checked (about a second after launch), so a refusal of the command
line stays one line (``serve`` says it before building the board, whose geometric mechanics
compiles as it is built: on a cold cache a port that cannot be opened is refused after it);
``skinhil compile`` compiles ahead of time.
"""

from __future__ import annotations

import sys

COLD_COMPILE_S = (15, 30)
"""Seconds (fastest, slowest) a cold compile of the board's kernels is announced to take: what
``skinhil compile`` takes on an empty cache on the 2-core machines the project targets."""


KERNEL_ROOMS: dict[str, tuple[str, ...]] = {
    "simulate": ("model",),
    "train": ("model",),
}
"""Whose kernels each command runs (numba names a cache folder after the package that holds
the kernels): the model's, and the wire's (protocols) unless listed here."""


def cache_is_cold(command: str = "serve") -> tuple[bool, str]:
    """(the kernels ``command`` runs are not cached yet for this source version, the cache
    directory)."""
    from protocols.kernel_cache import CACHE_DIR

    rooms = KERNEL_ROOMS.get(command, ("model", "protocols"))
    cold = not all(any(CACHE_DIR.glob(f"{room}_*/*.nbi")) for room in rooms)
    return cold, str(CACHE_DIR)


def announce_cold_cache(command: str) -> None:
    """On a cold kernel cache, say on stderr that ``command`` compiles first and about how
    long it takes (nothing when the cache is warm). Each command calls it once its input is
    checked, just before its first kernel runs: a refusal stays one line."""
    cold, where = cache_is_cold(command)
    if cold:
        lo, hi = COLD_COMPILE_S
        print(f"skinhil {command}: compiling the model's and the link's kernels for this "
              f"version of the sources, about {lo}-{hi} s before it starts (once; cached in "
              f"{where}; 'skinhil compile' does it ahead of time)", file=sys.stderr, flush=True)
