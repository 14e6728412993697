"""Compactness and speed of the wire protocols (serial, classic CAN, CAN FD).

Run: ``python benchmarks/bench_protocols.py [--smoke] [--results-dir DIR]``
(pinned to one core; ``--smoke``:
0.05 s of spikes, one run each, to check the script runs). For Poisson spikes over
338 channels at 100 µs steps, with frames flushed every 1 ms (one ``events`` call per ms, as
the board does) and a status record every 100 ms, it reports
- serial bytes per event, framing, SYNC and status included (targets ≤ 2.5 at 20k ev/s,
  ≤ 2.2 at 100k ev/s);
- classic CAN and CAN FD events per events frame and per frame of any kind, and the bus
  time they need (1 Mbit/s classic; FD 1 Mbit/s arbitration, 2 Mbit/s data, worst-case
  stuffing) (targets ≥ 3 per 8-byte frame, ≥ 28 per 64-byte frame at load);
- encode and decode speed in events/s on one core, per-ms calls and one bulk call
  (target ≥ 1M events/s).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe, pin_one_core  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

pin_one_core()

import numpy as np  # noqa: E402

from protocols import (  # noqa: E402
    CanDecoder,
    CanEncoder,
    SerialDecoder,
    SerialEncoder,
    Status,
    can_frame_seconds,
)
from skinhil.events import make_events  # noqa: E402

STEP_US = 100
FLUSH_US = 1000
STATUS_US = 100_000
DURATION_S = 2.0
REPEATS = 3


def poisson_events(rate_hz: float, duration_s: float, seed: int = 0) -> np.ndarray:
    """Spikes of 338 independent Poisson channels at ``rate_hz`` events/s in total."""
    rng = np.random.default_rng(seed)
    n_steps = int(round(duration_s * 1e6 / STEP_US))
    p = rate_hz / 338 * STEP_US * 1e-6
    raster = rng.random((n_steps, 338)) < p
    step, addr = np.nonzero(raster)
    return make_events(step * STEP_US, addr)


def chunks(events: np.ndarray, duration_s: float) -> list[tuple[np.ndarray, int]]:
    """The events split into 1 ms flushes: (events, t_end_us) per call."""
    ends = np.arange(FLUSH_US, int(duration_s * 1e6) + 1, FLUSH_US)
    cut = np.searchsorted(events["t"], ends)
    starts = np.concatenate([[0], cut[:-1]])
    return [(events[a:b], int(e)) for a, b, e in zip(starts, cut, ends, strict=True)]


def status_at(t_us: int, n: int) -> Status:
    return Status(t_us, n, n, 0, 0, 0, 0, True)


def stream(enc: SerialEncoder | CanEncoder, parts: list[tuple[np.ndarray, int]]) -> list:
    """Encode per-ms flushes plus a status every 100 ms; return the per-call outputs."""
    out = []
    sent = 0
    for ev, t_end in parts:
        out.append(enc.events(ev, t_end))
        sent += len(ev)
        if t_end % STATUS_US == 0:
            out.append(enc.status(status_at(t_end, sent)))
    return out


def best(fn: Callable[[], object]) -> float:
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def serial_report(rate: float) -> list[dict]:
    ev = poisson_events(rate, DURATION_S)
    parts = chunks(ev, DURATION_S)
    data = b"".join(stream(SerialEncoder(), parts))
    n = len(ev)
    print(f"serial   {rate / 1e3:5.0f}k ev/s: {len(data) / n:.3f} bytes/event "
          f"({len(data)} B for {n} events in {DURATION_S} s; "
          f"{len(data) / DURATION_S / 92160:.0%} of 921600 baud)")
    t_enc = best(lambda: [SerialEncoder().events(e, t) for e, t in parts])
    t_bulk = best(lambda: SerialEncoder().events(ev, int(DURATION_S * 1e6)))
    pieces = [data[i:i + 256] for i in range(0, len(data), 256)]

    def dec_chunks() -> None:
        d = SerialDecoder()
        for p in pieces:
            d.feed(p)

    t_dec = best(dec_chunks)
    t_dec_bulk = best(lambda: SerialDecoder().feed(data))
    check = SerialDecoder().feed(data).events
    assert len(check) == n
    print(f"         encode {n / t_enc / 1e6:.2f} M ev/s (1 ms calls), "
          f"{n / t_bulk / 1e6:.2f} M ev/s (one call); decode {n / t_dec / 1e6:.2f} M ev/s "
          f"(256-byte reads), {n / t_dec_bulk / 1e6:.2f} M ev/s (one read)")
    k = f"{rate / 1e3:.0f}k ev/s"
    return [figure(f"serial bytes per event at {k}", round(len(data) / n, 3), "B/event",
                   "≤ 2.5" if rate <= 20_000 else "≤ 2.2"),
            figure(f"serial encode at {k}, 1 ms calls", round(n / t_enc / 1e6, 2), "M ev/s",
                   "≥ 1"),
            figure(f"serial decode at {k}, 256-byte reads", round(n / t_dec / 1e6, 2),
                   "M ev/s", "≥ 1")]


def can_report(rate: float, fd: bool) -> list[dict]:
    ev = poisson_events(rate, DURATION_S)
    parts = chunks(ev, DURATION_S)
    frames = [f for out in stream(CanEncoder(fd=fd), parts) for f in out]
    n = len(ev)
    ev_frames = [f for f in frames if f.arbitration_id >> 4 == 6]
    full = sum(1 for f in ev_frames if len(f.data) == (64 if fd else 8))
    bus_s = sum(can_frame_seconds(f, 1_000_000, 2_000_000 if fd else None) for f in frames)
    name = "CAN FD " if fd else "CAN    "
    print(f"{name}  {rate / 1e3:5.0f}k ev/s: {n / len(ev_frames):.2f} events/events frame "
          f"({full / len(ev_frames):.0%} full), {n / len(frames):.2f} events/frame of any kind; "
          f"bus load {bus_s / DURATION_S:.0%}")
    t_enc = best(lambda: [CanEncoder(fd=fd).events(e, t) for e, t in parts])
    t_bulk = best(lambda: CanEncoder(fd=fd).events(ev, int(DURATION_S * 1e6)))
    batches = [frames[i:i + 64] for i in range(0, len(frames), 64)]

    def dec_batches() -> None:
        d = CanDecoder(fd=fd)
        for b in batches:
            d.feed(b)

    t_dec = best(dec_batches)
    t_dec_bulk = best(lambda: CanDecoder(fd=fd).feed(frames))
    assert len(CanDecoder(fd=fd).feed(frames).events) == n
    print(f"         encode {n / t_enc / 1e6:.2f} M ev/s (1 ms calls), "
          f"{n / t_bulk / 1e6:.2f} M ev/s (one call); decode {n / t_dec / 1e6:.2f} M ev/s "
          f"(64-frame batches), {n / t_dec_bulk / 1e6:.2f} M ev/s (one batch)")
    k = f"{name.strip()} at {rate / 1e3:.0f}k ev/s"
    return [figure(f"{k}: events per events frame", round(n / len(ev_frames), 2), "events/frame",
                   "≥ 28" if fd else "≥ 3"),
            figure(f"{k}: bus load", round(bus_s / DURATION_S, 3), "of bus time", ""),
            figure(f"{k}: encode, 1 ms calls", round(n / t_enc / 1e6, 2), "M ev/s", "≥ 1"),
            figure(f"{k}: decode, 64-frame batches", round(n / t_dec / 1e6, 2), "M ev/s",
                   "≥ 1")]


def main() -> None:
    global DURATION_S, REPEATS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke", action="store_true", help="0.05 s, one run each: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        DURATION_S, REPEATS = 0.05, 1
    print(describe())
    print(f"Poisson spikes over 338 channels, {STEP_US} µs steps, flush every {FLUSH_US} µs, "
          f"status every {STATUS_US // 1000} ms, {DURATION_S} s; speeds best of {REPEATS}")
    # warm the compiled kernels
    small = poisson_events(20_000, 0.01)
    SerialDecoder().feed(SerialEncoder().events(small, 10_000))
    for fd in (False, True):
        CanDecoder(fd=fd).feed(CanEncoder(fd=fd).events(small, 10_000))
    figures = []
    for rate in (20_000, 100_000):
        figures += serial_report(rate)
    for rate in (20_000, 30_000, 100_000):
        figures += can_report(rate, fd=False)
    for rate in (20_000, 100_000):
        figures += can_report(rate, fd=True)
    publish(args, "protocols", "Wire protocols: compactness and codec speed", figures)


if __name__ == "__main__":
    main()
