"""Benchmark: a whole hand live over UDP, the board on one core and ``listen`` on the other
(a script, not a test).

``skinhil listen --udp PORT --size S --json`` (PSP filter bank, onset detection and a
decision per detected stimulus, with a decoder of the skin's shape) runs pinned to one core
(``taskset``); once it has started up, a board ``skinhil serve --udp 127.0.0.1:PORT --size S
--snr-db 10 --seed 1 --duration D --cpu C`` plays the default random schedule on the other.
Reported: the events the board generated, sent and dropped against those listen decoded and
counted lost on the link or late; the board's late ticks (ticks that ended after their
deadline) of all its ticks; listen's CPU time over the board's run (``/proc/PID/stat``, user +
system) as a share of its core; its decisions; the socket buffer listen's kernel granted; the
load average before and after.

The decoder is fitted in a second on random features (``chance_model``): its decisions are
chance, but it has the skin's shape, so the receiver does all the work a trained one does.

Usage::

    python benchmarks/bench_live_hand.py [--size 34x34] [--duration 60] [--board-cpu 0]
                                         [--listen-cpu 1] [--snr-db 10] [--smoke]
                                         [--results-dir DIR]

``--smoke``: 6x6 for 1 s (checks that the script runs; its figures mean little).
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from harness.lab import chance_model  # noqa: E402
from harness.serve import ServeProcess  # noqa: E402
from machine import describe, load_average  # noqa: E402
from process_cpu import cpu_while, settle  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402


def free_udp_port() -> int:
    """A UDP port of 127.0.0.1 free at this moment."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def started(board: ServeProcess, timeout_s: float = 600.0) -> None:
    """Wait for the board's first status line (``--json``): its kernels are compiled and its
    clock runs."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and not board.exited:
        if any(x.get("type") == "status" for x in list(board.lines)):
            return
        time.sleep(0.01)
    raise SystemExit(f"the board did not start: {board.stderr[-2000:]}")


def run(size: str, duration: float, board_cpu: int, listen_cpu: int, snr_db: str,
        model: Path, profile: Path | None = None) -> dict[str, Any]:
    """One session; its figures as a dict. ``profile``: py-spy records listen there (SVG)."""
    port = free_udp_port()
    listen = ServeProcess("--udp", f"127.0.0.1:{port}", "--model", str(model), "--json",
                          "--size", size, command="listen")
    board = None
    try:
        os.sched_setaffinity(listen.proc.pid, {listen_cpu})
        settle(listen.proc.pid)
        load_before = os.getloadavg()
        board = ServeProcess("--udp", f"127.0.0.1:{port}", "--size", size, "--snr-db", snr_db,
                             "--seed", "1", "--duration", str(duration), "--cpu",
                             str(board_cpu), "--json")
        started(board)
        spy = None if profile is None else subprocess.Popen(
            ["py-spy", "record", "-r", "50", "-d", str(int(duration)), "-o", str(profile),
             "-p", str(listen.proc.pid)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        rc, cpu, wall = cpu_while(listen.proc.pid, lambda: board.wait(duration + 600), 0.5)
        listen.interrupt()
        listen.wait(120)
        if spy is not None:
            spy.wait(60)
    finally:
        listen.kill()
        if board is not None:
            board.kill()
    if rc != 0:
        raise SystemExit(f"the board stopped with {rc}: {board.stderr[-2000:]}")
    s = board.summary()
    info = listen.summary()
    link = info["link"]
    decisions = sum(1 for x in listen.lines if x.get("type") == "decision")
    return {
        "size": size, "duration_s": duration, "board_time_s": s["board_time_s"],
        "board_wall_s": round(s["wall_s"], 2),
        "board_generated": s["generated"], "board_sent": s["sent"],
        "board_dropped_by": {k: v for k, v in s["dropped_by"].items() if v},
        "late_ticks": s["deadline_misses"], "ticks": s["ticks"],
        "late_ticks_pct": round(100 * s["deadline_misses"] / max(s["ticks"], 1), 3),
        "board_cpu_share": round(s["cpu_s"] / max(s["wall_s"], 1e-9), 3),
        "events_decoded": link["events_decoded"], "lost_on_link": link["lost_on_link"],
        "frames_lost": link["frames_lost"], "late_events": link["late_events"],
        "all_decoded": link["events_decoded"] == s["sent"] and link["lost_on_link"] == 0,
        "decisions": decisions, "socket_buffer": info.get("socket_buffer"),
        "listen_cpu_share": round(cpu / wall, 4),
        "listen_cpu_s_per_board_s": round(cpu / max(s["board_time_s"], 1e-9), 4),
        "load_before": [round(v, 2) for v in load_before],
        "load_after": [round(v, 2) for v in os.getloadavg()],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="34x34", help="skin size ROWSxCOLS (34x34)")
    ap.add_argument("--duration", type=float, default=60.0, help="board seconds (60)")
    ap.add_argument("--board-cpu", type=int, default=0, help="the board's core (0)")
    ap.add_argument("--listen-cpu", type=int, default=1, help="listen's core (1)")
    ap.add_argument("--snr-db", default="10", help="neuron noise SNR, dB (10)")
    ap.add_argument("--profile", type=Path, metavar="SVG",
                    help="record listen with py-spy (pip install py-spy) into this flame graph")
    ap.add_argument("--smoke", action="store_true", help="6x6 for 1 s: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.size, args.duration = "6x6", 1.0
    cores = os.sched_getaffinity(0)
    for name in ("board_cpu", "listen_cpu"):
        if getattr(args, name) not in cores:
            ap.error(f"--{name.replace('_', '-')} {getattr(args, name)}: not one of this "
                     f"machine's cores {sorted(cores)}")
    print(describe(), flush=True)
    print(load_average(), flush=True)
    rows, cols = (int(v) for v in args.size.split("x"))
    with tempfile.TemporaryDirectory(prefix="bench-hand-") as tmp:
        model = chance_model(Path(tmp), (rows, cols))
        res = run(args.size, args.duration, args.board_cpu, args.listen_cpu, args.snr_db,
                  model, args.profile)
    print(json.dumps(res), flush=True)
    print(f"{res['size']}: {res['events_decoded']} of {res['board_sent']} events sent decoded "
          f"({res['board_generated']} generated), {res['lost_on_link']} lost on the link, "
          f"{res['late_events']} late; board late ticks {res['late_ticks']} of "
          f"{res['ticks']} ({res['late_ticks_pct']} %); listen "
          f"{100 * res['listen_cpu_share']:.1f} % of its core "
          f"({res['listen_cpu_s_per_board_s']:.3f} CPU s per board s); {res['decisions']} "
          f"decisions; socket buffer {res['socket_buffer']}", flush=True)
    print(load_average(), flush=True)
    publish(args, f"live_hand_{res['size']}", f"A whole hand live over UDP: {res['size']} for "
            f"{args.duration:g} s at {args.snr_db} dB", [
                figure("events sent", res["board_sent"], "events"),
                figure("events decoded", res["events_decoded"], "events", "every event sent"),
                figure("lost on the link", res["lost_on_link"], "events", "0"),
                figure("late at the receiver", res["late_events"], "events"),
                figure("board late ticks", res["late_ticks_pct"], f"% of {res['ticks']} ticks",
                       "≤ 0.5"),
                figure("listen CPU", round(100 * res["listen_cpu_share"], 1), "% of its core",
                       "≤ 70"),
                figure("listen CPU per second of board time",
                       res["listen_cpu_s_per_board_s"], "s/s"),
                figure("decisions", res["decisions"], "decisions")])
    return 0


if __name__ == "__main__":
    sys.exit(main())
