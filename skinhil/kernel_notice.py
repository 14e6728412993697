"""The cold kernel cache notice: code about to run kernels that are not compiled yet says
so, for about how long, and where they will be cached, once per process.

The model's and the wire's kernels are compiled on first use and cached on disk
(:mod:`protocols.kernel_cache`: ``$NUMBA_CACHE_DIR``, else ``skinhil/__pycache__/numba``
next to the sources, else the user's cache folder; one directory per version of the
sources). The first run after an install or a change of the sources spends
:data:`COLD_COMPILE_S` compiling before it starts. The command line prints
:func:`cold_cache_message` once its input is checked (:mod:`skinhil.cli.kernel_notice`);
the notebook API (:mod:`skinhil.api`) wraps its board's warm-up in :func:`compiling`,
which logs the same message at INFO and shows a tqdm bar of the seconds spent.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Iterator

log = logging.getLogger(__name__)

COLD_COMPILE_S = (15, 30)
"""Seconds (fastest, slowest) a cold compile of the board's kernels is announced to take: what
``skinhil compile`` takes on an empty cache on the 2-core machines the project targets."""

KERNEL_ROOMS: dict[str, tuple[str, ...]] = {
    "simulate": ("model",),
    "train": ("model",),
}
"""Whose kernels each command runs (numba names a cache folder after the package that holds
the kernels): the model's, and the wire's (protocols) unless listed here."""

BAR_PERIOD_S = 0.5
"""How often (s) the compile bar moves."""

_announced: set[str] = set()
"""The users (commands, API classes) already announced in this process."""


def cache_is_cold(command: str = "serve") -> tuple[bool, str]:
    """(the kernels ``command`` runs are not cached yet for this source version, the cache
    directory)."""
    from protocols.kernel_cache import CACHE_DIR

    rooms = KERNEL_ROOMS.get(command, ("model", "protocols"))
    cold = not all(any(CACHE_DIR.glob(f"{room}_*/*.nbi")) for room in rooms)
    return cold, str(CACHE_DIR)


def cold_cache_message(command: str) -> str | None:
    """What ``skinhil COMMAND`` (or the API's ``command``) says before its first kernel runs
    on a cold cache, once per process; None when the cache is warm or it was said."""
    cold, where = cache_is_cold(command)
    if not cold or command in _announced:
        return None
    _announced.add(command)
    lo, hi = COLD_COMPILE_S
    return (f"skinhil {command}: compiling the model's and the link's kernels for this "
            f"version of the sources, about {lo}-{hi} s before it starts (once; cached in "
            f"{where}; 'skinhil compile' does it ahead of time)")


@contextlib.contextmanager
def compiling(command: str) -> Iterator[None]:
    """Around code that runs ``command``'s kernels first (a board's warm-up): on a cold
    cache, the notice at INFO and a tqdm bar of the seconds spent (on stderr, up to the
    slowest of :data:`COLD_COMPILE_S`) until the body returns; nothing on a warm one."""
    message = cold_cache_message(command)
    if message is None:
        yield
        return
    log.info(message)
    from tqdm.auto import tqdm

    done = threading.Event()
    bar = tqdm(total=COLD_COMPILE_S[1], desc="compiling kernels", leave=False,
               bar_format="{desc}: {bar} {n:.0f} of about {total} s")

    def tick() -> None:
        while not done.wait(BAR_PERIOD_S):
            bar.update(min(BAR_PERIOD_S, bar.total - bar.n))

    ticker = threading.Thread(target=tick, name="skinhil-compile-bar", daemon=True)
    ticker.start()
    try:
        yield
    finally:
        done.set()
        ticker.join()
        bar.close()
