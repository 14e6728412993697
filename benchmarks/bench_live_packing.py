"""How full the LIVE board's frames are under a sustained heavy touch (a script, not a test).

The board runs in real time (:class:`firmware_sim.board.Board`, the code ``skinhil serve``
runs) on its default random schedule of the 9 force directions with no rest between
stimuli (``rest_s`` 0: one touch after another) at ``--snr-db`` (default -5 dB: about 4,400
events/s, more than classic CAN carries at 125 kbit/s; at the paper's 10 dB the same touch
gives about 600 events/s), and everything it puts on the link is captured and counted:

1. classic CAN at 125 kbit/s and CAN FD at 125 kbit/s (no bit-rate switch), on a python-can
   ``virtual`` bus (the board paces itself to the bitrate; a sniffer on the bus sees every
   frame): events per EVENTS frame, the share of full frames, non-full frames per flush
   (tick), events/s sent and dropped;
2. serial over a real pty at 921600 and 115200 baud: bytes per event received (framing,
   SYNC, 10 Hz status and markers included).

Usage::

    python benchmarks/bench_live_packing.py [--duration 10] [--snr-db -5] [--can-only]
                                            [--smoke] [--results-dir DIR]

``--smoke``: 0.3 s per run, serial at 921600 baud only (checks that the script runs).
"""

from __future__ import annotations

import argparse
import random
import sys
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from conftest import PtyPair  # noqa: E402
from harness.peers import PtyPeer  # noqa: E402
from machine import describe, load_average  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import protocols  # noqa: E402
from firmware_sim.board import Board, BoardConfig, BoardSummary  # noqa: E402
from skinhil.transports import CanTransport, SerialTransport  # noqa: E402

EVENTS_CLASS = 6


def _config(args: argparse.Namespace) -> BoardConfig:
    return BoardConfig(snr_db=args.snr_db, rest_s=0.0, seed=1)


def _can_run(args: argparse.Namespace, fd: bool) -> tuple[BoardSummary, list[Any]]:
    chan = f"bench-{random.getrandbits(32)}"
    sniffer = CanTransport(chan, "virtual", fd=fd)
    frames: list[Any] = []
    done = threading.Event()

    def sniff() -> None:
        while not done.is_set():
            frames.extend(sniffer.recv(timeout=0.1))

    reader = threading.Thread(target=sniff, daemon=True)
    reader.start()
    board = Board(_config(args), lambda: CanTransport(chan, "virtual", fd=fd,
                                                      bitrate=args.bitrate))
    summary = board.run(args.duration)
    time.sleep(0.5)
    done.set()
    reader.join()
    frames.extend(sniffer.recv(timeout=0.2))
    sniffer.shutdown()
    return summary, frames


def _can_line(name: str, s: BoardSummary, frames: list[Any], fd: bool
              ) -> tuple[str, list[dict[str, Any]]]:
    """The run's line and its figures."""
    dec = protocols.CanDecoder(fd=fd)
    per_frame = []
    for f in frames:
        if f.arbitration_id >> 4 == EVENTS_CLASS:
            per_frame.append(len(dec.feed([f]).events))
        else:
            dec.feed([f])
    full = 40 if fd else 4
    n_full = sum(n == full for n in per_frame)
    ticks = s.ticks
    ev = sum(per_frame)
    per = ev / max(1, len(per_frame))
    figures = [figure(f"{name}: events per EVENTS frame", round(per, 2), "events/frame",
                      "" if fd else "≥ 3.5"),
               figure(f"{name}: full EVENTS frames", round(100 * n_full / max(1, len(per_frame)),
                                                           1), "%"),
               figure(f"{name}: events sent", round(s.sent / s.board_time_s), "events/s"),
               figure(f"{name}: events generated", round(s.generated / s.board_time_s),
                      "events/s")]
    return (f"{name}: {s.board_time_s:.0f} s board time; generated "
            f"{s.generated / s.board_time_s:.0f} ev/s, sent {s.sent / s.board_time_s:.0f} ev/s, "
            f"dropped {s.dropped_by}; {len(per_frame)} EVENTS frames carrying {ev} events: "
            f"{ev / max(1, len(per_frame)):.2f} events per frame (full = {full}), "
            f"{100 * n_full / max(1, len(per_frame)):.1f}% full, "
            f"{(len(per_frame) - n_full) / ticks:.2f} non-full frames per flush (tick); "
            f"decoder events_lost {dec.counters.events_lost}; wire busy "
            f"{100 * s.wire_busy_s / s.wall_s:.0f}% of the run; deadline misses "
            f"{s.deadline_misses} of {ticks} ticks"), figures


def _serial_run(args: argparse.Namespace, baud: int) -> tuple[str, list[dict[str, Any]]]:
    """The run's line and its figures."""
    pair = PtyPair()
    peer = PtyPeer(pair.master)
    try:
        board = Board(_config(args), lambda: SerialTransport(pair.path, baud=baud))
        s = board.run(args.duration)
        time.sleep(0.5)
    finally:
        peer.close()
        pair.close()
    got = len(peer.events)
    name = f"serial {baud} baud (pty)"
    figures = [figure(f"{name}: bytes per event received", round(peer.raw_units / max(1, got),
                                                                   2), "B/event"),
               figure(f"{name}: events sent", round(s.sent / s.board_time_s), "events/s")]
    return (f"serial {baud} baud (pty): {s.board_time_s:.0f} s board time; generated "
            f"{s.generated / s.board_time_s:.0f} ev/s, sent {s.sent / s.board_time_s:.0f} ev/s, "
            f"dropped {s.dropped_by}; received {got} events in {peer.raw_units} bytes: "
            f"{peer.raw_units / max(1, got):.2f} bytes per event; wire busy "
            f"{100 * s.wire_busy_s / s.wall_s:.0f}% of the run; deadline misses "
            f"{s.deadline_misses} of {s.ticks} ticks"), figures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="board seconds per run (10)")
    ap.add_argument("--snr-db", type=float, default=-5.0, help="neuron noise SNR (-5 dB)")
    ap.add_argument("--bitrate", type=int, default=125_000, help="CAN bitrate (125000)")
    ap.add_argument("--can-only", action="store_true", help="no serial runs")
    ap.add_argument("--smoke", action="store_true", help="0.3 s per run: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.duration = 0.3
    print(describe(), flush=True)
    figures = []
    for fd in (False, True):
        s, frames = _can_run(args, fd)
        name = f"{'CAN FD' if fd else 'classic CAN'} {args.bitrate // 1000} kbit/s"
        line, more = _can_line(name, s, frames, fd)
        print(line, flush=True)
        print("  " + load_average(), flush=True)
        figures += more
    for baud in () if args.can_only else (921600,) if args.smoke else (921600, 115200):
        line, more = _serial_run(args, baud)
        print(line, flush=True)
        print("  " + load_average(), flush=True)
        figures += more
    publish(args, "live_packing", f"Live board's frames under a sustained touch at "
            f"{args.snr_db:g} dB, {args.duration:g} s per run", figures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
