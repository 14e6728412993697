"""End-to-end latency: spike time on the board → event decoded at the receiver, and the
decision latency from onset, over a pty and (where vcan0 exists) over vcan.

The board runs as ``skinhil serve`` in a subprocess; its tick clock starts at the host's
monotonic time (CLOCK_MONOTONIC is system-wide on Linux), announced by the first status
record: the event latency of a spike at board time t is (host time decoded) − (board start
+ t), including the board's 1 ms publish tick, the wire budget and the receiver's decoding.
The board start is estimated as the smallest (arrival − board time) seen, so the figures
are latencies above the fastest delivery (a lower bound on the true latency, exact up to
that minimum).

    python benchmarks/bench_latency.py [--snr-db 10] [--duration 20] [--links pty,vcan]
                                       [--smoke] [--results-dir DIR]

``--smoke``: 1.5 s over the pty, a decoder of 1 stimulus per condition without its
cross-validation (checks that the script runs; its figures mean little).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

from skinhil.receiver import Receiver, ReceiverListener, WindowDecoder  # noqa: E402
from skinhil.receiver.session import run_against_board, serve_command  # noqa: E402
from skinhil.receiver.training import train_decoder  # noqa: E402
from skinhil.transports import PtyMasterTransport  # noqa: E402


class Arrivals(ReceiverListener):
    """(board time µs, host arrival s) of every decoded event."""

    def __init__(self) -> None:
        self.t_us: list[np.ndarray] = []
        self.host_s: list[np.ndarray] = []

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        self.t_us.append(events["t"].copy())
        self.host_s.append(np.full(len(events), host_time_s))


def measure(receiver: Receiver, arrivals: Arrivals) -> dict[str, float]:
    t = np.concatenate(arrivals.t_us) * 1e-6
    h = np.concatenate(arrivals.host_s)
    lag = h - t
    lag -= lag.min()
    sb = receiver.scoreboard
    dec_b, dec_h = sb.latencies_s(), sb.latencies_s(host=True)
    return {"events": float(len(t)), "event_p50_ms": 1e3 * float(np.percentile(lag, 50)),
            "event_p99_ms": 1e3 * float(np.percentile(lag, 99)),
            "decision_board_p50_ms": 1e3 * float(np.percentile(dec_b, 50)),
            "decision_board_p99_ms": 1e3 * float(np.percentile(dec_b, 99)),
            "decision_host_p50_ms": 1e3 * float(np.percentile(dec_h, 50)),
            "decision_host_p99_ms": 1e3 * float(np.percentile(dec_h, 99)),
            "accuracy": sb.accuracy, "stimuli": float(sb.scored)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--rest", type=float, default=0.25, help="board rest after each stimulus")
    ap.add_argument("--reps", type=int, default=15, help="training stimuli per condition")
    ap.add_argument("--links", default="pty,vcan", help="links to measure (vcan if present)")
    ap.add_argument("--smoke", action="store_true", help="1.5 s over the pty: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.duration, args.reps, args.rest, args.links = 1.5, 1, 0.05, "pty"
    print(describe())
    decoder, report = train_decoder(args.snr_db, args.reps, seed=0, rest_s=args.rest,
                                    cross_validation=not args.smoke)
    wd = WindowDecoder(decoder)
    print(f"offline accuracy at {args.snr_db:g} dB (board-like windows): "
          f"{report.accuracy:.3f} of {report.markers} stimuli")
    figures = [figure(f"offline accuracy at {args.snr_db:g} dB", round(report.accuracy, 3),
                      f"of {report.markers} stimuli")]
    links = [k for k in args.links.split(",") if k == "pty"
             or (k == "vcan" and os.path.exists("/sys/class/net/vcan0"))]
    for kind in links:
        arrivals = Arrivals()
        if kind == "pty":
            link, slave = PtyMasterTransport.open_pair()
            receiver = Receiver(link, wd, listeners=[arrivals])
            cmd = serve_command(["--port", link.slave_path], args.duration, args.snr_db, 3,
                                args.rest)
        else:
            from skinhil.transports import CanTransport

            link, slave = CanTransport("vcan0"), -1
            receiver = Receiver(link, wd, listeners=[arrivals])
            cmd = serve_command(["--can", "vcan0"], args.duration, args.snr_db, 3, args.rest)
        try:
            status, _, err = run_against_board(receiver, cmd)
        finally:
            link.shutdown()
            if slave >= 0:
                os.close(slave)
        if status != 0:
            print(f"{kind}: board failed: {err.strip()}")
            continue
        m = measure(receiver, arrivals)
        print(f"{kind}: {int(m['events'])} events; event latency above the fastest p50 "
              f"{m['event_p50_ms']:.2f} ms p99 {m['event_p99_ms']:.2f} ms; decision latency "
              f"from onset (board time) p50 {m['decision_board_p50_ms']:.1f} ms p99 "
              f"{m['decision_board_p99_ms']:.1f} ms, (host) p50 {m['decision_host_p50_ms']:.1f}"
              f" ms p99 {m['decision_host_p99_ms']:.1f} ms; online accuracy "
              f"{m['accuracy']:.3f} over {int(m['stimuli'])} stimuli")
        figures += [figure(f"{kind}: events", int(m["events"]), "events"),
                    figure(f"{kind}: event latency above the fastest, p50",
                           round(m["event_p50_ms"], 2), "ms"),
                    figure(f"{kind}: event latency above the fastest, p99",
                           round(m["event_p99_ms"], 2), "ms"),
                    figure(f"{kind}: decision latency from onset, board time, p50",
                           round(m["decision_board_p50_ms"], 1), "ms"),
                    figure(f"{kind}: decision latency from onset, board time, p99",
                           round(m["decision_board_p99_ms"], 1), "ms"),
                    figure(f"{kind}: decision latency from onset, host time, p50",
                           round(m["decision_host_p50_ms"], 1), "ms"),
                    figure(f"{kind}: decision latency from onset, host time, p99",
                           round(m["decision_host_p99_ms"], 1), "ms"),
                    figure(f"{kind}: online accuracy", round(m["accuracy"], 3),
                           f"of {int(m['stimuli'])} stimuli")]
    publish(args, "latency", "End-to-end latency: board spike to decoded event, onset to "
            "decision", figures)
    return 0 if args.smoke or not math.isnan(report.accuracy) else 1


if __name__ == "__main__":
    sys.exit(main())
