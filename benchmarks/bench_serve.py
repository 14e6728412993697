"""Benchmark of ``skinhil serve`` (a script, not a test).

Runs the board as a subprocess, as a user would, and reports from its own summary:

1. defaults over a 921600-baud pty for ``--duration`` s (default 60): CPU share of one core,
   tick lateness p50/p99/max, deadline misses, events/s;
2. sustained events/s through the 921600-baud pty when the neurons fire far more than the
   link carries (``--snr-db 20``): the link is the limit, the FIFO drops the rest;
3. the same through a 1 Mbit/s vcan0 (classic CAN), inside user-mode Linux when this host
   has no CAN. System calls there are slow (about 0.3 ms per CAN send), so that figure is a
   lower bound for the board, not the bus.

Usage::

    python benchmarks/bench_serve.py [--duration 60] [--skip-vcan] [--realtime] [--smoke]
                                     [--results-dir DIR]

``--smoke``: the defaults for 1 s on the pty, nothing else (checks that the script runs).

Each pty run also reports how busy the whole machine was meanwhile (from /proc/stat) and
the load average: tick lateness on a shared machine says more about the others than about
the board, unless it runs with ``--realtime``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from conftest import PtyPair  # noqa: E402
from harness.peers import CanPeer, PtyPeer  # noqa: E402
from harness.serve import ServeProcess  # noqa: E402
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402
from uml_vcan import host_has_can, in_uml, run_in_uml  # noqa: E402


def _cpu_times() -> tuple[float, float]:
    """(busy, total) jiffies of all CPUs since boot, from /proc/stat (0, 0 if unknown)."""
    try:
        with open("/proc/stat", encoding="ascii") as fh:
            vals = [float(v) for v in fh.readline().split()[1:]]
    except OSError:
        return 0.0, 0.0
    idle = vals[3] + (vals[4] if len(vals) > 4 else 0.0)
    return sum(vals) - idle, sum(vals)


def _machine_load(t0: tuple[float, float]) -> str:
    """How busy the whole machine was since ``t0`` (all cores), and the load average."""
    busy, total = _cpu_times()
    share = (busy - t0[0]) / (total - t0[1]) if total > t0[1] else float("nan")
    la = os.getloadavg()
    return (f"machine during the run: {100 * share:.0f}% of all {os.cpu_count()} cores busy "
            f"(this run included); load average {la[0]:.2f} {la[1]:.2f} {la[2]:.2f}")


def _pty_run(duration: float, *extra: str) -> dict:
    pair = PtyPair()
    serve = ServeProcess("--port", pair.path, "--baud", "921600", "--duration", str(duration),
                         "--json", *extra)
    peer = PtyPeer(pair.master)
    try:
        serve.wait(duration + 120)
        time.sleep(0.2)
    finally:
        serve.kill()
        peer.close()
        pair.close()
    s = serve.summary()
    s["received_events"] = len(peer.events)
    s["received_bytes"] = peer.raw_units
    return s


def _vcan_run(duration: float, *extra: str) -> dict:
    peer = CanPeer("vcan0")
    serve = ServeProcess("--can", "vcan0", "--duration", str(duration), "--json", *extra)
    try:
        serve.wait(duration + 120)
        time.sleep(0.5)
    finally:
        serve.kill()
        peer.close()
    s = serve.summary()
    s["received_events"] = len(peer.events)
    s["received_frames"] = peer.raw_units
    s["rx_overflows"] = peer.bus.rx_overflows
    return s


def _line(name: str, s: dict) -> str:
    lat = s["lateness_ms"]
    return (f"{name}: {s['board_time_s']:.0f} s board time in {s['wall_s']:.1f} s; CPU "
            f"{100 * s['cpu_s'] / s['wall_s']:.1f}% of one core; lateness p50 {lat['p50']:.3f} "
            f"p99 {lat['p99']:.3f} max {lat['max']:.3f} ms; deadline misses "
            f"{s['deadline_misses']} of {s['ticks']} ticks; generated "
            f"{s['generated'] / s['board_time_s']:.0f} ev/s, sent "
            f"{s['sent'] / s['board_time_s']:.0f} ev/s, received "
            f"{s['received_events'] / s['board_time_s']:.0f} ev/s; dropped {s['dropped_by']}")


def _figures(name: str, s: dict, defaults: bool = False, realtime: bool = False
             ) -> list[dict]:
    """The figures of one run's summary; the CPU target holds at the defaults, the lateness
    target at the defaults with ``--realtime``."""
    lat, bt = s["lateness_ms"], s["board_time_s"]
    return [figure(f"{name}: CPU", round(100 * s["cpu_s"] / s["wall_s"], 1), "% of one core",
                   "≤ 25" if defaults else ""),
            figure(f"{name}: tick lateness p50", round(lat["p50"], 3), "ms"),
            figure(f"{name}: tick lateness p99", round(lat["p99"], 3), "ms",
                   "≤ 0.5" if defaults and realtime else ""),
            figure(f"{name}: tick lateness max", round(lat["max"], 3), "ms"),
            figure(f"{name}: deadline misses", s["deadline_misses"], f"of {s['ticks']} ticks"),
            figure(f"{name}: events sent", round(s["sent"] / bt), "events/s"),
            figure(f"{name}: events received", round(s["received_events"] / bt), "events/s")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="seconds per run (60)")
    ap.add_argument("--skip-vcan", action="store_true", help="no vcan run")
    ap.add_argument("--vcan-only", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--realtime", action="store_true",
                    help="serve with --realtime (FIFO scheduling; needs root or CAP_SYS_NICE)")
    ap.add_argument("--smoke", action="store_true",
                    help="the defaults for 1 s on the pty only: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.duration, args.skip_vcan = 1.0, True
    rt = ["--realtime"] if args.realtime else []
    if args.vcan_only:  # inside UML (or on a host with vcan0): print one JSON summary
        print("RESULT " + json.dumps(_vcan_run(args.duration, "--snr-db", "20", *rt)))
        return 0
    print(describe())
    tag = " --realtime" if rt else ""
    benchmark = "serve_realtime" if rt else "serve"
    title = f"skinhil serve{tag}: {args.duration:g} s per run"
    t0 = _cpu_times()
    s = _pty_run(args.duration, *rt)
    print(_line(f"defaults{tag}, 921600-baud pty", s), flush=True)
    print("  " + _machine_load(t0), flush=True)
    figures = _figures("defaults, 921600-baud pty", s, defaults=True, realtime=bool(rt))
    if args.smoke:
        publish(args, benchmark, title, figures)
        return 0
    t0 = _cpu_times()
    s = _pty_run(args.duration, "--snr-db", "20", *rt)
    print(_line(f"saturated (--snr-db 20){tag}, 921600-baud pty", s), flush=True)
    print("  " + _machine_load(t0), flush=True)
    figures += _figures("saturated (--snr-db 20), 921600-baud pty", s)
    if args.skip_vcan:
        publish(args, benchmark, title, figures)
        return 0
    cmd = [sys.executable, str(Path(__file__).resolve()), "--vcan-only", "--duration",
           str(args.duration), *rt]
    if host_has_can("vcan0") or in_uml():
        where = "host vcan0"
        import subprocess
        out = subprocess.run(cmd, capture_output=True, text=True).stdout
    else:
        where = "vcan0 inside user-mode Linux (slow system calls)"
        res = run_in_uml(cmd, ROOT, timeout_s=args.duration + 300)
        out = res.output
        print(f"user-mode Linux: boot {res.boot_s:.2f} s, total {res.total_s:.1f} s")
    result = [ln for ln in out.splitlines() if ln.startswith("RESULT ")]
    if not result:
        print(f"vcan run failed:\n{out}")
        publish(args, benchmark, title, figures)
        return 1
    s = json.loads(result[-1][7:])
    print(_line(f"saturated (--snr-db 20){tag}, 1 Mbit/s classic CAN, {where}", s))
    print(f"  frames received {s['received_frames']}, reader overflows {s['rx_overflows']}")
    figures += _figures(f"saturated (--snr-db 20), 1 Mbit/s classic CAN, {where}", s)
    publish(args, benchmark, title, figures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
