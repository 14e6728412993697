"""The receiver's filters on a backlog: the cost of 1 s of stream whatever the chunk it comes in.

Run: ``python benchmarks/bench_receiver_backlog.py [--seconds 12] [--block-steps N] [--smoke]
[--results-dir DIR]``
(``--smoke``: 0.4 s of stream in chunks of 0.02 and 0.2 s, to check the script runs); inside
user-mode Linux: ``python tests/uml_vcan.py -- python benchmarks/bench_receiver_backlog.py``.
The same board stream (``board_stream``, 10 dB, seed 3; 338 channels at 0.1 ms) is pushed into
a fresh :class:`skinhil.receiver.online.OnlineClassifier` in chunks of 0.02 s (a receiver
keeping up) to 4 s (a receiver that fell seconds behind reads its whole backlog at once), and
each pass reports its time per second of stream and the minor page faults it took.

A receiver whose cost per second of stream grows with the backlog never catches up once
behind: the next backlog is larger. Target: every chunk size well under 1 s per 1 s of
stream, and no chunk size costlier than the smallest by more than a few times.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import skinhil.receiver.online as online  # noqa: E402
from skinhil.receiver import WindowDecoder  # noqa: E402
from skinhil.receiver.training import board_stream, train_decoder  # noqa: E402

CHUNKS_S = (0.02, 0.2, 1.0, 4.0)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=12.0, help="stream length (s)")
    p.add_argument("--block-steps", type=int, default=online.MAX_BLOCK_STEPS,
                   help="steps filtered per block at most (default: the receiver's)")
    p.add_argument("--smoke", action="store_true", help="0.4 s of stream: the script runs")
    add_arguments(p)
    args = p.parse_args()
    chunks_s = CHUNKS_S
    if args.smoke:
        args.seconds, chunks_s = 0.4, CHUNKS_S[:2]
    online.MAX_BLOCK_STEPS = args.block_steps
    model, _ = train_decoder(10.0, reps=1 if args.smoke else 2, seed=0, rest_s=0.05,
                             cross_validation=False)
    decoder = WindowDecoder(model)
    events = np.concatenate([b[0] for b in board_stream(args.seconds, 10.0, 0.25, 3)])
    warm = online.OnlineClassifier(decoder)
    warm.advance(500_000)  # numba kernels loaded before anything is timed
    print(describe())
    figures = []
    print(f"{events.shape[0]} events in {args.seconds:g} s, blocks of {args.block_steps} steps")
    for chunk_s in chunks_s:
        clf = online.OnlineClassifier(decoder)
        edges = np.arange(0.0, args.seconds + 1e-9, chunk_s)
        r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
        decisions = 0
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            sel = (events["t"] >= a * 1e6) & (events["t"] < b * 1e6)
            clf.push(events[sel])
            decisions += len(clf.advance(int(round(b * 1e6))))
        spent = time.perf_counter() - t0
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0.ru_minflt
        print(f"chunks of {chunk_s:4.2f} s: {spent / args.seconds:.3f} s per s of stream, "
              f"{faults} minor page faults, {decisions} decisions")
        figures += [figure(f"chunks of {chunk_s:g} s: time per second of stream",
                           round(spent / args.seconds, 3), "s/s", "< 0.1"),
                    figure(f"chunks of {chunk_s:g} s: minor page faults", faults,
                           f"faults in {args.seconds:g} s")]
    publish(args, "receiver_backlog", f"Receiver on a backlog: blocks of {args.block_steps} "
            "steps", figures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
