"""Benchmark: what the live view and the LSL outlets add to ``skinhil listen`` (a script,
not a test).

For each skin size, a board (``skinhil serve --size S --snr-db 10``) plays ``--duration``
s on a socat pty pair to ``skinhil listen --json`` twice: once alone, once with ``--view 0
--lsl`` while this process consumes both outputs as a lab would (one page's update stream
over HTTP, read and parsed; a pylsl inlet on every outlet, loopback only). Reported per run:
the CPU time of the listen process over the board's run (``/proc/PID/stat``, user + system)
as a share of one core and per second of board time (the same when the board keeps real
time), the events the board generated against those the receiver decoded
(and lost, late), the view's updates per second and spikes it could not carry, and the
samples every LSL inlet read.

Usage::

    python benchmarks/bench_lab_outputs.py [--sizes 6x6,26x26] [--duration 30]
                                           [--psp-sensors LIST] [--baud N]
                                           [--configs none,view,lsl,view+lsl]
                                           [--smoke] [--results-dir DIR]

``--smoke``: 6x6 for 1 s, listen alone, with a decoder fitted on random features
(``chance_model``) instead of a trained one (checks that the script runs).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from harness.host_link import linked_ptys  # noqa: E402
from harness.lab import LOOPBACK_LSL_CFG, chance_model, quick_model, wait_for_stderr  # noqa: E402
from harness.serve import ServeProcess  # noqa: E402
from machine import describe, load_average  # noqa: E402
from process_cpu import cpu_while, settle  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402


class PageReader:
    """Reads the view's update stream as a page does: each update parsed as JSON."""

    def __init__(self, url: str) -> None:
        self.updates = 0
        self.not_drawn = 0
        self.spikes = 0
        self.first: float | None = None
        self.last: float | None = None
        self._resp = urllib.request.urlopen(url + "events", timeout=30)
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        event = None
        try:
            for raw in self._resp:
                line = raw.decode().rstrip("\n")
                if line.startswith("event: "):
                    event = line[7:]
                elif line.startswith("data: ") and event == "update":
                    msg = json.loads(line[6:])
                    self.updates += 1
                    self.spikes += msg["spikes"]["n"]
                    self.not_drawn += msg["spikes"]["not_drawn"]
                    now = time.monotonic()
                    self.first = self.first or now
                    self.last = now
        except (OSError, ValueError):
            pass


class LslReaders:
    """A pylsl inlet on every outlet of ``name``, pulled on threads; samples counted."""

    def __init__(self, name: str) -> None:
        import pylsl

        self.counts: dict[str, int] = {}
        self._stop = threading.Event()
        self._threads = []
        for kind in ("spikes", "psp", "markers", "decisions", "link"):
            info = pylsl.resolve_byprop("name", f"{name}-{kind}", timeout=10)[0]
            inlet = pylsl.StreamInlet(info, max_buflen=360)
            inlet.open_stream(10)
            self.counts[kind] = 0
            t = threading.Thread(target=self._pull, args=(kind, inlet), daemon=True)
            t.start()
            self._threads.append(t)

    def _pull(self, kind: str, inlet: Any) -> None:
        import numpy as np

        n = inlet.channel_count
        numeric = kind in ("spikes", "psp", "link")  # into a numpy buffer, as a lab would
        rows = max(1, min(200_000, 4_000_000 // n))
        kinds = {"psp": np.float32, "link": np.float64}
        dest = np.empty((rows, n), kinds.get(kind, np.int32)) if numeric else None
        while not self._stop.is_set():
            _, stamps = inlet.pull_chunk(timeout=0.05, max_samples=rows, dest_obj=dest)
            self.counts[kind] += len(stamps)

    def close(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(5)


CONFIGS = {"none": [], "view": ["--view", "0"], "lsl": ["--lsl", "bench"],
           "view+lsl": ["--view", "0", "--lsl", "bench"]}
"""The listen runs compared: alone, with each output, with both."""


def first_events(listen: ServeProcess, board: ServeProcess, timeout_s: float = 600.0) -> None:
    """Wait for listen's first link line (``--json``, every second) with events decoded, or
    for the board's end (a run shorter than listen's first line: listen ends with it)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if board.exited:
            return
        if any(x.get("type") == "link" and x.get("events_decoded", 0) > 0
               for x in list(listen.lines)):
            return
        time.sleep(0.02)
    raise SystemExit(f"no events reached listen: {listen.stderr[-2000:]}\nthe board: "
                     f"{board.stderr[-2000:]}")


def run(size: str, duration: float, config: str, model: Path, tmp: Path,
        psp_sensors: str | None, baud: int) -> dict[str, Any]:
    extra = list(CONFIGS[config])
    outputs = bool(extra)
    if outputs and psp_sensors:
        extra += ["--psp-sensors", psp_sensors]
    with linked_ptys(tmp) as (board_end, host_end):
        listen = ServeProcess("--port", str(host_end), "--baud", str(baud), "--model",
                              str(model), "--json", "--size", size, *extra, command="listen")
        page = lsl = None
        try:
            if "--view" in extra:
                page = PageReader(wait_for_stderr(listen, "live view at").split()[-1])
            if "--lsl" in extra:
                wait_for_stderr(listen, "LSL outlets")
                lsl = LslReaders("bench")
            settle(listen.proc.pid)
            board = ServeProcess("--port", str(board_end), "--baud", str(baud),
                                 "--duration", str(duration),
                                 "--size", size, "--snr-db", "10", "--seed", "1", "--json")
            first_events(listen, board)
            rc, cpu, wall = cpu_while(listen.proc.pid, lambda: board.wait(duration + 600), 1.0)
            listen.interrupt()
            listen.wait(120)
            if lsl is not None:
                time.sleep(1.0)
                lsl.close()
        finally:
            listen.kill()
    if rc != 0:
        raise SystemExit(f"the board stopped with {rc}: {board.stderr[-2000:]}")
    link = listen.summary()["link"]
    out = {"size": size, "outputs": config, "wall_s": round(wall, 2),
           "listen_cpu_share": round(cpu / wall, 4),
           "listen_cpu_s_per_board_s": round(cpu / duration, 4),
           "board_generated": board.summary().get("generated"),
           "board_wall_s": round(board.summary().get("wall_s", 0.0), 2),
           "board_dropped_by": {k: v for k, v in board.summary().get("dropped_by", {}).items()
                                if v},
           "events_decoded": link["events_decoded"], "lost_on_link": link["lost_on_link"],
           "late_events": link["late_events"], "board_dropped": link["board_dropped"]}
    if page is not None and page.first is not None and page.last is not None:
        out.update(view_updates_per_s=round(page.updates / max(1e-9, page.last - page.first),
                                            2), view_spikes=page.spikes,
                   view_not_drawn=page.not_drawn)
    if lsl is not None:
        out.update(lsl_samples=dict(lsl.counts))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="6x6,26x26")
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--psp-sensors", help="passed to listen with the outputs")
    ap.add_argument("--baud", type=int, default=921600,
                    help="the board's serial budget, bits/s (a pty carries any)")
    ap.add_argument("--configs", default="none,view+lsl",
                    help=f"listen runs to compare, of {', '.join(CONFIGS)}")
    ap.add_argument("--smoke", action="store_true", help="6x6 for 1 s: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.sizes, args.duration, args.configs = "6x6", 1.0, "none"
    if shutil.which("socat") is None:
        raise SystemExit("socat is needed (apt-get install socat)")
    print(describe())
    tmp = Path(tempfile.mkdtemp(prefix="bench-lab-"))
    cfg = tmp / "lsl_api.cfg"
    cfg.write_text(LOOPBACK_LSL_CFG)
    os.environ["LSLAPICFG"] = str(cfg)
    figures: list[dict[str, Any]] = []
    for size in args.sizes.split(","):
        rows, cols = (int(v) for v in size.split("x"))
        model = (chance_model if args.smoke else quick_model)(tmp, (rows, cols))
        for config in args.configs.split(","):
            print(load_average(), flush=True)
            res = run(size, args.duration, config, model, tmp, args.psp_sensors, args.baud)
            print(json.dumps(res), flush=True)
            figures += run_figures(res)
    print(load_average())
    publish(args, "lab_outputs", "What the live view and the LSL outlets add to listen",
            figures)


def run_figures(res: dict[str, Any]) -> list[dict[str, Any]]:
    """The figures of one listen run (:func:`run`'s record)."""
    k = f"{res['size']}, listen with {res['outputs']}"
    out = [figure(f"{k}: listen CPU per second of board time", res["listen_cpu_s_per_board_s"],
                  "s/s"),
           figure(f"{k}: events generated by the board", res["board_generated"] or 0, "events"),
           figure(f"{k}: events decoded", res["events_decoded"], "events"),
           figure(f"{k}: lost on the link", res["lost_on_link"], "events", "0"),
           figure(f"{k}: late at the receiver", res["late_events"], "events")]
    if "view_updates_per_s" in res:
        out += [figure(f"{k}: view updates", res["view_updates_per_s"], "updates/s"),
                figure(f"{k}: spikes the view could not draw", res["view_not_drawn"],
                       "spikes")]
    out += [figure(f"{k}: LSL samples read, {name}", n, "samples")
            for name, n in res.get("lsl_samples", {}).items()]
    return out


if __name__ == "__main__":
    main()
