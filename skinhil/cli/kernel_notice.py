"""The command line's cold kernel cache notice (:mod:`skinhil.kernel_notice` holds the rule
and the message, which the notebook API logs as well).

``serve``, ``listen``, ``demo``, ``train`` and ``simulate`` call :func:`announce_cold_cache`
once their input is checked (about a second after launch), so a refusal of the command
line stays one line (``serve`` says it before building the board, whose geometric mechanics
compiles as it is built: on a cold cache a port that cannot be opened is refused after it);
``skinhil compile`` compiles ahead of time.
"""

from __future__ import annotations

import sys

from skinhil.kernel_notice import COLD_COMPILE_S, KERNEL_ROOMS, cache_is_cold, cold_cache_message

__all__ = ["COLD_COMPILE_S", "KERNEL_ROOMS", "announce_cold_cache", "cache_is_cold"]


def announce_cold_cache(command: str) -> None:
    """On a cold kernel cache, say on stderr that ``command`` compiles first and about how
    long it takes (nothing when the cache is warm). Each command calls it once its input is
    checked, just before its first kernel runs: a refusal stays one line."""
    message = cold_cache_message(command)
    if message is not None:
        print(message, file=sys.stderr, flush=True)
