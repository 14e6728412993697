"""The closed loop's end-to-end latency: a spike on the board → the receiver → a GRIP → the
skin's contact force, over a pty, UDP and (where vcan0 exists) vcan.

The board runs as ``skinhil serve --grasp LIFTS`` in a subprocess; the host here reads its
stream and, whenever no GRIP of its own is outstanding, answers the newest spike it has
decoded with a GRIP (alternately 0.35 and 0.3 N, within the board's rate bound), noting that
spike's board time. The board logs each GRIP with the board time it executed it (its
``--score`` file, ``grasp.grip_log``); the grip acts from the next step on (the tick's first
step, one step of ``dt`` later: the contact's normal force moves there, tests/test_grasp_loop.py).
So the loop's latency, all in board time, is

    executed_us + dt − spike_us

the board's 1 ms publish tick, the link both ways, the host's decoding and the board's
command poll (once a tick) included. A ``--smoke`` run plays two short lifts on a pty.

    python benchmarks/bench_grasp_loop.py [--lifts 3] [--links pty,udp,vcan] [--smoke]
                                             [--results-dir DIR]
    python tests/uml_vcan.py -- python benchmarks/bench_grasp_loop.py --links vcan
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import protocols  # noqa: E402
from skinhil.plant import GraspParams  # noqa: E402
from skinhil.receiver.answer import host_encoder  # noqa: E402
from skinhil.receiver.grip_loop import GripLoop  # noqa: E402
from skinhil.receiver.receiver import ReceiverListener  # noqa: E402
from skinhil.receiver.session import run_against_board, serve_command  # noqa: E402
from skinhil.transports import PtyMasterTransport, Transport  # noqa: E402

DT_US = 100
"""The board's step (µs): the grip acts on the contact from the step after its tick."""


class Answerer(ReceiverListener):
    """Answers the newest decoded spike with a GRIP whenever none is outstanding."""

    def __init__(self, transport: Transport[Any]) -> None:
        self.transport = transport
        self.encoder = host_encoder(transport, 0)
        self.token = 0
        self.outstanding = False
        self.sent_s = 0.0
        self.spike_us: dict[int, int] = {}
        self.answers: dict[int, int] = {}
        """ACKs by reason (0: executed)."""

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        if not len(events) or (self.outstanding and host_time_s - self.sent_s < 0.1):
            return  # one GRIP at a time (one whose answer is 0.1 s late is given up)
        self.token += 1
        grip = 0.35 if self.token % 2 else 0.3
        payload = self.encoder.command(protocols.Command(self.token, protocols.CommandCode.GRIP,
                                                         grip))
        if self.transport.send(payload, timeout=0.5) == len(payload):
            self.spike_us[self.token] = int(events["t"][-1])
            self.outstanding = True
            self.sent_s = host_time_s

    def on_ack(self, ack: Any) -> None:
        if ack.opcode == protocols.CommandCode.GRIP:
            self.answers[int(ack.reason)] = self.answers.get(int(ack.reason), 0) + 1
            if ack.token == self.token:
                self.outstanding = False


def measure(kind: str, lifts: int, snr_db: float) -> dict[str, float] | None:
    """One run over ``kind`` (pty, udp, vcan): latency percentiles (ms) and the count."""
    slave = -1
    if kind == "pty":
        link: Transport[Any] = PtyMasterTransport.open_pair()[0]
        assert isinstance(link, PtyMasterTransport)
        args = ["--port", link.slave_path]
    elif kind == "udp":
        from skinhil.transports.udp import UdpTransport

        link = UdpTransport("127.0.0.1", 0, listen=True)
        args = ["--udp", f"127.0.0.1:{link.port}"]
    else:
        from skinhil.transports import CanTransport

        link = CanTransport("vcan0", fd=True)
        args = ["--can", "vcan0", "--fd"]
    answerer = Answerer(link)
    with tempfile.TemporaryDirectory() as tmp:
        score = Path(tmp) / "score.json"
        duration = round(lifts * GraspParams().period_s, 3)
        cmd = serve_command([*args, "--grasp", str(lifts), "--score", str(score)], duration,
                            snr_db, 5)
        try:
            status, _, err = run_against_board(GripLoop(link, [answerer]), cmd)
        finally:
            link.shutdown()
            if slave >= 0:
                os.close(slave)
        if status != 0 or not score.exists():
            print(f"{kind}: board failed: {err.strip()[-400:]}")
            return None
        log = json.loads(score.read_text(encoding="utf-8"))["grasp"]["grip_log"]
    lat = np.array([(applied + DT_US - answerer.spike_us[token]) * 1e-3
                    for token, _, applied, _ in log if token in answerer.spike_us])
    if not len(lat):
        print(f"{kind}: {answerer.token} GRIPs sent, none executed; ACKs by reason "
              f"{answerer.answers}")
        return None
    return {"grips": float(len(lat)), "sent": float(answerer.token),
            "p50_ms": float(np.percentile(lat, 50)), "p90_ms": float(np.percentile(lat, 90)),
            "p99_ms": float(np.percentile(lat, 99)),
            "max_ms": float(lat.max())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--lifts", type=int, default=3)
    ap.add_argument("--links", default="pty,udp,vcan", help="links (vcan where vcan0 exists)")
    ap.add_argument("--smoke", action="store_true", help="two lifts on a pty (a quick check)")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.lifts, args.links = 2, "pty"
    print(describe())
    failed = 0
    figures = []
    for kind in args.links.split(","):
        if kind == "vcan" and not os.path.exists("/sys/class/net/vcan0"):
            print("vcan: no vcan0 here (python tests/uml_vcan.py -- python "
                  "benchmarks/bench_grasp_loop.py --links vcan)")
            continue
        m = measure(kind, args.lifts, args.snr_db)
        if m is None or m["grips"] == 0:
            failed += 1
            continue
        print(f"{kind}: {int(m['grips'])} of {int(m['sent'])} GRIPs executed; spike on the "
              f"board -> contact force: p50 {m['p50_ms']:.2f} ms, p90 {m['p90_ms']:.2f} ms, "
              f"p99 {m['p99_ms']:.2f} ms, "
              f"max {m['max_ms']:.2f} ms (board time; {args.lifts} lifts at "
              f"{args.snr_db:g} dB)", flush=True)
        figures += [figure(f"{kind}: GRIPs executed", int(m["grips"]),
                           f"of {int(m['sent'])} sent")]
        figures += [figure(f"{kind}: spike on the board to contact force, {q}",
                           round(m[f"{q}_ms"], 2), "ms board time") for q in
                    ("p50", "p90", "p99", "max")]
    publish(args, "grasp_loop", f"Closed loop: spike to GRIP to contact force, {args.lifts} "
            f"lifts at {args.snr_db:g} dB", figures)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
