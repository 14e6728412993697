"""``skinhil compile``: compile and cache the numba kernels ahead of time, so that the first
real run starts at once (:mod:`skinhil.cli.kernel_notice` says when a run has to compile)."""

from __future__ import annotations

import argparse
import os
import time

from protocols import kernel_cache
from skinhil.cli.conventions import add_json_option, print_json
from skinhil.cli.kernel_notice import cache_is_cold
from skinhil.errors import ConfigError


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "compile", help="compile the numba kernels now (the first run of serve, listen, "
                        "demo, train and simulate then starts at once)",
        description="Compile and cache every numba kernel of the board (skin, neurons, "
                    "stimuli, serial and CAN encoders) and of the receiver (serial and CAN "
                    "decoders, PSP filter), so that the first real run starts at once. "
                    "Takes 15-60 s on a cold cache, about a second on a warm one.")
    add_json_option(p)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from firmware_sim.board import Board, BoardConfig
    from protocols import SerialDecoder, SerialEncoder
    from skinhil.events import make_events
    from skinhil.model.psp import PSPFilterBank
    from skinhil.transports import SerialTransport

    where = kernel_cache.CACHE_DIR
    if not (where.is_dir() and os.access(where, os.W_OK | os.X_OK)):
        raise ConfigError(f"the kernel cache '{where}' cannot be written — set NUMBA_CACHE_DIR "
                          "to a writable folder (without a cache every run compiles again)")
    t0 = time.monotonic()
    board = Board(BoardConfig(), lambda: SerialTransport("loop://"), None,
                  lambda _: None)
    board.run(0.01)  # the board's warm-up runs the model and the serial link once
    events = make_events(np.arange(8, dtype=np.int64) * 100, np.arange(8))
    SerialDecoder().feed(SerialEncoder().events(events, 1000))
    bank = PSPFilterBank(4, 1e-3)
    bank.step_block(np.zeros((2, 4)))
    bank.step_events(2, np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros((2, 4)))
    cold, cached = cache_is_cold()
    if cold:
        raise ConfigError(f"the kernels compiled but were not cached in '{cached}' — set "
                          "NUMBA_CACHE_DIR to a writable folder")
    seconds = time.monotonic() - t0
    if args.json:
        print_json({"cache": str(cached), "seconds": round(seconds, 3)})
    else:
        print(f"kernels compiled and cached in {cached} in {seconds:.1f} s")
    return 0
