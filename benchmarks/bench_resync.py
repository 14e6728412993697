"""Serial decoder on adversarial byte streams: resynchronisation is linear in time and memory.

Run: ``python benchmarks/bench_resync.py [--mb 32] [--smoke] [--results-dir DIR]``
(pinned to one core;
``--smoke``: 0.1 MB of the first pattern, to check the script runs). For each pattern it
feeds ``--mb`` MB to a fresh :class:`protocols.SerialDecoder` in one ``feed()`` call, in a
fresh interpreter (after a small warm-up feed, so numba's compilation is not timed), and
reports the rate in MB/s and the peak memory the call added (the peak resident size,
``VmHWM``, reset just before it, less the resident size before it) as a multiple of its
input. Targets (SPEC.md §6): every adversarial pattern at ≥ 10 MB/s and ≤ 4x its input.

Patterns: ``runs01`` (``0x01`` × 1031 + ``0x00``: every suffix is a COBS chain), ``runsff``
(``0xFF`` × 1031 + ``0x00``), ``longrun`` (no delimiter at all), ``storm`` (``0x00`` only),
``storm01`` (``0x01 0x00`` repeated), ``random`` (uniform bytes), ``packets`` (a real
narrow stream, 20k events/s Poisson, for comparison).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe, load_average, pin_one_core  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

PATTERNS = ("runs01", "runsff", "longrun", "storm", "storm01", "random", "packets")

_CHILD = r"""
import json, sys, time
import numpy as np
import protocols
from skinhil.events import make_events

name, size = sys.argv[1], int(sys.argv[2])
def pattern(name, size):
    rng = np.random.default_rng(0)
    if name == "runs01":
        unit = b"\x01" * 1031 + b"\x00"
    elif name == "runsff":
        unit = b"\xff" * 1031 + b"\x00"
    elif name == "longrun":
        return b"\x05" * size
    elif name == "storm":
        return bytes(size)
    elif name == "storm01":
        unit = b"\x01\x00"
    elif name == "random":
        return rng.integers(0, 256, size, dtype=np.uint8).tobytes()
    else:
        enc = protocols.SerialEncoder()
        out, t0 = bytearray(), 0
        while len(out) < size:
            raster = rng.random((10, 338)) < 20_000 / 338 * 1e-4
            step, addr = np.nonzero(raster)
            out += enc.events(make_events((step + t0) * 100, addr), (t0 + 10) * 100)
            t0 += 10
        return bytes(out[:size])
    return (unit * (size // len(unit) + 1))[:size]

protocols.SerialDecoder().feed(pattern(name, 100_000))  # compile and warm up
data = pattern(name, size)
def status_kb(field):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith(field))
with open("/proc/self/clear_refs", "w") as fh:  # resets the peak (VmHWM) to the current RSS
    fh.write("5")
rss0 = status_kb("VmRSS:")
dec = protocols.SerialDecoder()
t = time.perf_counter()
res = dec.feed(data)
dt = time.perf_counter() - t
added_kb = status_kb("VmHWM:") - rss0
c = dec.counters
print(json.dumps({"pattern": name, "mb": size / 1e6, "seconds": dt, "mb_s": size / 1e6 / dt,
                  "added_x": added_kb * 1024 / size, "events": len(res.events),
                  "frames_ok": c.frames_ok, "crc_errors": c.crc_errors,
                  "resyncs": c.resyncs, "discarded": c.bytes_discarded}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mb", type=float, default=32.0, help="input per pattern (MB)")
    ap.add_argument("--patterns", default=",".join(PATTERNS))
    ap.add_argument("--smoke", action="store_true",
                    help="0.1 MB of the first pattern: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.mb, args.patterns = 0.1, PATTERNS[0]
    pin_one_core()
    print(describe())
    print(load_average(), "(before)")
    size = int(args.mb * 1e6)
    print(f"{'pattern':9s} {'MB':>6s} {'s':>7s} {'MB/s':>7s} {'mem x':>6s}  counters")
    figures = []
    for name in args.patterns.split(","):
        res = subprocess.run([sys.executable, "-c", _CHILD, name, str(size)],
                             capture_output=True, text=True, check=True)
        r = json.loads(res.stdout.strip().splitlines()[-1])
        print(f"{name:9s} {r['mb']:6.1f} {r['seconds']:7.2f} {r['mb_s']:7.1f} "
              f"{r['added_x']:6.2f}  ok {r['frames_ok']} crc {r['crc_errors']} resyncs "
              f"{r['resyncs']} discarded {r['discarded']} events {r['events']}")
        adversarial = name != "packets"
        figures += [figure(f"{name}: decode rate, {r['mb']:g} MB in one feed",
                           round(r["mb_s"], 1), "MB/s", "≥ 10" if adversarial else ""),
                    figure(f"{name}: peak memory added", round(r["added_x"], 2), "x input",
                           "≤ 4" if adversarial else "")]
    print(load_average(), "(after)")
    publish(args, "resync", "Serial decoder on adversarial byte streams", figures)


if __name__ == "__main__":
    main()
