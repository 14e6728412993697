"""``skinhil compile``: compile the numba kernels ahead of time, and the cold-cache notice.

The model's and the wire's kernels are compiled on first use and cached on disk
(:mod:`protocols.kernel_cache`: ``$NUMBA_CACHE_DIR`` or ``skinhil/__pycache__/numba`` next
to the sources, one directory per version of the sources). The first run after an install
or a change of the sources spends :data:`COLD_COMPILE_S` compiling before its first tick;
:func:`announce_cold_cache` says so at once, and ``skinhil compile`` does it ahead of time.
"""

from __future__ import annotations

import argparse
import sys
import time

COLD_COMPILE_S = (15, 30)
"""Seconds a cold compile of the board's kernels takes on a 2-core VM (16 s measured for
``serve`` at load 0.8; up to ~30 s on a loaded machine)."""


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
    long it takes (nothing when the cache is warm)."""
    cold, where = cache_is_cold(command)
    if cold:
        lo, hi = COLD_COMPILE_S
        print(f"skinhil {command}: compiling the model's and the link's kernels for this "
              f"version of the sources, about {lo}-{hi} s before it starts (once; cached in "
              f"{where}; 'skinhil compile' does it ahead of time)", file=sys.stderr, flush=True)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "compile", help="compile the numba kernels now (the first run of serve, listen, "
                        "demo, train and simulate then starts at once)",
        description="Compile and cache every numba kernel of the board (skin, neurons, "
                    "stimuli, serial and CAN encoders) and of the receiver (serial and CAN "
                    "decoders, PSP filter), so that the first real run starts at once. "
                    "Takes 15-60 s on a cold cache, about a second on a warm one.")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from firmware_sim.board import Board, BoardConfig
    from protocols import SerialDecoder, SerialEncoder
    from skinhil.events import make_events
    from skinhil.model.psp import PSPFilterBank
    from skinhil.transports import SerialTransport

    t0 = time.monotonic()
    board = Board(BoardConfig(), lambda: SerialTransport("loop://", 921600), None,
                  lambda _: None)
    board.run(0.01)  # the board's warm-up runs the model and the serial link once
    events = make_events(np.arange(8, dtype=np.int64) * 100, np.arange(8))
    SerialDecoder().feed(SerialEncoder().events(events, 1000))
    PSPFilterBank(4, 1e-3).step_block(np.zeros((2, 4)))
    cold, where = cache_is_cold()
    print(f"kernels compiled and cached in {where} in {time.monotonic() - t0:.1f} s")
    return 1 if cold else 0
