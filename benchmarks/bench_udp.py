"""Benchmark of ``skinhil serve --udp`` on loopback (a script, not a test).

For each skin size, runs the board as a subprocess (``skinhil serve --udp 127.0.0.1:PORT``)
for ``--duration`` s and decodes every datagram in this process with the protocols decoder
(no classifier: its cost is the receiver's, see bench_latency.py). Reports whether the board
kept real time (wall time, deadline misses, tick lateness, CPU share of one core), the event
rates, the bytes per event on the wire and the loss accounting: events decoded against the
board's own final status (``events_sent``) and the decoder's ``events_lost``.

Usage::

    python benchmarks/bench_udp.py [--sizes 6x6,32x32] [--duration 60] [--snr-db DB]
                                   [--threads N] [--realtime] [--cpu N] [--smoke]
                                   [--results-dir DIR]

``--smoke``: the default skin for 1 s (checks that the script runs).

``--sizes`` needs ``skinhil serve --size``; 6x6 is the default skin either way. ``--cpu N``
runs the board on core N (``serve --cpu N``) and this process, the receiver, on the others:
a board with its core to itself, as firmware, and its receiver beside it.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from harness.serve import ServeProcess  # noqa: E402
from machine import describe, load_average  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import protocols  # noqa: E402
from skinhil.transports import UdpTransport  # noqa: E402


class CountingHost:
    """Decodes every datagram on a UDP port of 127.0.0.1 and keeps counts, not events."""

    cores: set[int] | None = None
    """The cores the receiving thread runs on (None: any)."""

    def __init__(self) -> None:
        self.link = UdpTransport("127.0.0.1", 0, listen=True)
        self.decoder = protocols.SerialDecoder()
        self.events = 0
        self.bytes = 0
        self.datagrams = 0
        self.last_status: Any = None
        self.max_addr = -1
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        if self.cores is not None:
            os.sched_setaffinity(0, self.cores)  # this thread only
        while not self._stop.is_set():
            grams = self.link.recv_from(timeout=0.05)
            for _, data in grams:
                self.datagrams += 1
                self.bytes += len(data)
                res = self.decoder.feed(data)
                self.events += len(res.events)
                if len(res.events):
                    self.max_addr = max(self.max_addr, int(res.events["addr"].max()))
                for rec in res.records:
                    if isinstance(rec, protocols.Status):
                        self.last_status = rec

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.link.shutdown()


def run(size: str | None, duration: float, extra: list[str]
        ) -> tuple[str, list[dict[str, Any]]]:
    """One size's run: its lines and its figures (none when serve failed)."""
    host = CountingHost()
    args = ["--udp", f"127.0.0.1:{host.link.port}", "--duration", str(duration), "--json",
            *(["--size", size] if size else []), *extra]
    serve = ServeProcess(*args)
    try:
        rc = serve.wait(duration + 600)
        time.sleep(0.5)
    finally:
        serve.kill()
        host.close()
    if rc != 0:
        return f"{size or '6x6'}: serve failed ({rc}): {serve.stderr.strip()[-300:]}", []
    s = serve.summary()
    c = host.decoder.counters
    st = host.last_status
    bt = s["board_time_s"]
    lat = s["lateness_ms"]
    exact = st is not None and st.events_sent == host.events and c.events_lost == 0
    figures = [figure("board time over wall time", round(bt / s["wall_s"], 3), "x real time",
                      "1"),
               figure("deadline misses", s["deadline_misses"], f"of {s['ticks']} ticks"),
               figure("tick lateness p50", round(lat["p50"], 3), "ms"),
               figure("tick lateness p99", round(lat["p99"], 3), "ms", "≤ 1"),
               figure("tick lateness max", round(lat["max"], 3), "ms"),
               figure("board CPU", round(100 * s["cpu_s"] / s["wall_s"]), "% of one core"),
               figure("events sent", round(s["sent"] / bt), "events/s"),
               figure("events decoded", round(host.events / bt), "events/s"),
               figure("bytes per event on the wire", round(host.bytes / max(host.events, 1), 2),
                      "B/event"),
               figure("loss accounting", "exact" if exact else "NOT exact", "status vs decoded",
                      "exact")]
    return (f"{size or '6x6'}: {bt:.0f} s board time in {s['wall_s']:.1f} s wall; deadline "
            f"misses {s['deadline_misses']} of {s['ticks']} ticks; lateness p50 "
            f"{lat['p50']:.3f} p99 {lat['p99']:.3f} max {lat['max']:.3f} ms; CPU "
            f"{100 * s['cpu_s'] / s['wall_s']:.0f}% of one core\n"
            f"  events: generated {s['generated'] / bt:.0f}/s, sent {s['sent'] / bt:.0f}/s, "
            f"decoded {host.events / bt:.0f}/s (highest channel {host.max_addr}); dropped "
            f"{s['dropped_by']}; wire {8 * host.bytes / bt / 1e6:.2f} Mbit/s, "
            f"{host.bytes / max(host.events, 1):.2f} bytes/event, "
            f"{host.datagrams / bt:.0f} datagrams/s\n"
            f"  loss accounting: final status sent {None if st is None else st.events_sent}, "
            f"decoded {host.events}, frames lost {c.frames_lost}, events lost "
            f"{c.events_lost}, CRC errors {c.crc_errors}: {'exact' if exact else 'NOT exact'}"
            f"\n  {load_average()}"), figures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="", help="comma-separated skin sizes, e.g. 6x6,32x32 "
                    "(default: the default skin)")
    ap.add_argument("--duration", type=float, default=60.0, help="seconds per run (60)")
    ap.add_argument("--snr-db", default=None, help="neuron noise SNR, dB (default: serve's)")
    ap.add_argument("--threads", default=None, help="serve --threads N (neuron threads)")
    ap.add_argument("--realtime", action="store_true",
                    help="serve with --realtime (FIFO scheduling; needs root or CAP_SYS_NICE)")
    ap.add_argument("--cpu", type=int, default=None,
                    help="the board on this core (serve --cpu), the receiver on the others")
    ap.add_argument("--smoke", action="store_true", help="6x6 for 1 s: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.sizes, args.duration = "", 1.0
    extra = (["--snr-db", args.snr_db] if args.snr_db else []) + (
        ["--threads", args.threads] if args.threads else []) + (
        ["--realtime"] if args.realtime else []) + (
        ["--cpu", str(args.cpu)] if args.cpu is not None else [])
    if args.cpu is not None:
        CountingHost.cores = os.sched_getaffinity(0) - {args.cpu}
        if not CountingHost.cores:
            ap.error(f"--cpu {args.cpu}: no other core is left for the receiver")
    print(describe(), flush=True)
    failed = 0
    for size in [s for s in args.sizes.split(",") if s] or [None]:
        line, figures = run(size, args.duration, extra)
        print(line, flush=True)
        if not figures:
            failed += 1
            continue
        publish(args, f"udp_{size or '6x6'}", f"skinhil serve --udp on loopback: {size or '6x6'}"
                f" for {args.duration:g} s{''.join(' ' + x for x in extra)}", figures)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
