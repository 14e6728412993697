"""Benchmark of record and replay (a script, not a test).

- ``pace``: a live board (``skinhil serve --port PTY --record rec.skcap``, and the same over
  UDP) is recorded for ``--duration`` s, then replayed in this process onto a second pty
  (UDP port) by :class:`skinhil.recording.Replayer`. Reports each unit's lateness (send start
  minus its due time on the recorded pace) and the inter-unit timing error (each interval
  between two units as sent minus as recorded), p50 / p99 / max.
- ``record``: the recording path of ``serve --record`` (:class:`RecordingTransport` into a
  .skcap capture, and into a CAN FD .blf log) fed a long stream at full speed:
  ``--events`` (default 10 million) synthetic events encoded in 1 ms flushes, as the board
  sends them. Reports the process's resident memory (VmRSS) before, at its peak, and after.
- ``session``: the recorder of ``listen --record`` (:class:`SessionRecorder`) fed the same
  events and saving the .npz: VmRSS from the first flush to the peak (VmHWM) of the save.
- ``listen``: ``skinhil listen --port PTY --record out.npz`` (a subprocess) fed the same
  long stream, as fast as it reads; its VmRSS sampled every 0.2 s from the first byte to
  its exit (the .npz written), and the events in the file counted; ``listen-control``: the
  same without ``--record`` (the receiver's own memory, which grows when it falls behind).

Usage::

    python benchmarks/bench_record_replay.py [--parts pace,record,session,listen,...]
                                             [--duration 20]
                                             [--events 10000000] [--smoke]
                                             [--results-dir DIR]

``--smoke``: the parts pace, record and session with 1 s of board time and 20,000 events
(checks that the script runs; its figures mean little).
"""

from __future__ import annotations

import argparse
import fcntl
import os
import signal
import subprocess
import sys
import tempfile
import termios
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "benchmarks")]

from conftest import PtyPair, PtyReader  # noqa: E402
from harness.serve import RUN_DIR, run_serve, serve_env  # noqa: E402
from machine import describe, load_average  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import protocols  # noqa: E402
from firmware_sim.clock import request_realtime  # noqa: E402
from protocols.events import make_events  # noqa: E402
from skinhil.recording import (  # noqa: E402
    RecordingTransport,
    Replayer,
    SessionRecorder,
    link_recorder,
    open_recording,
)
from skinhil.transports import SerialTransport, Transport, UdpTransport  # noqa: E402

EVENTS_PER_MS = 100
"""Synthetic stream: events per 1 ms flush (10 steps of 100 µs, 10 channels each)."""
MARKER_EVERY_MS = 500
WARM_TICKS = 1000
"""Memory is measured from this flush on (the first ones load the codec's kernels)."""


def rss_mb(pid: int | str = "self", field: str = "VmRSS") -> float:
    """Resident memory (MB) of process ``pid`` (VmRSS; ``field`` RssAnon: its anonymous
    part, RssFile: file pages mapped)."""
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            if line.startswith(f"{field}:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def pct(x: np.ndarray) -> str:
    x = np.asarray(x) * 1e3
    return (f"p50 {np.percentile(x, 50):.3f} ms, p99 {np.percentile(x, 99):.3f} ms, "
            f"max {x.max():.3f} ms")


def pct_figures(name: str, x: np.ndarray) -> list[dict[str, Any]]:
    """p50, p99 and max of ``x`` (s) as figures in ms."""
    x = np.asarray(x) * 1e3
    return [figure(f"{name} {q}", round(float(v), 3), "ms") for q, v in
            (("p50", np.percentile(x, 50)), ("p99", np.percentile(x, 99)), ("max", x.max()))]


# -- pace -------------------------------------------------------------------------------
def replay_pace(rec: Path, transport: Transport[Any], realtime: bool, link: str
                ) -> list[dict[str, Any]]:
    """Replay ``rec`` onto ``transport``; print and return its pace figures."""
    recording = open_recording(rec)
    if realtime:
        why = request_realtime()
        assert why is None, why
    replayer = Replayer(recording, transport)
    summary = replayer.run()
    if realtime:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    late = replayer.lateness_s()
    recorded = np.array([ts for ts, _ in recording.read()])
    interval_err = np.abs(np.diff(late))  # (sent interval) - (recorded interval)
    print(f"  {recording.units} units over {summary.recorded_s:.2f} s recorded, replayed in "
          f"{summary.wall_s:.2f} s; recorded intervals p50 "
          f"{np.percentile(np.diff(recorded), 50) * 1e3:.3f} ms")
    print(f"  lateness vs the recorded pace: {pct(late)}")
    print(f"  inter-unit timing error |sent - recorded interval|: {pct(interval_err)}")
    print(f"  {load_average()}")
    return (pct_figures(f"{link}: lateness vs the recorded pace", late)
            + pct_figures(f"{link}: inter-unit timing error", interval_err))


def part_pace(duration_s: float, tmp: Path, realtime: bool) -> list[dict[str, Any]]:
    print(f"\n[pace] serial: serve --port PTY --record, {duration_s:g} s; replay onto a "
          "second pty")
    rec = tmp / "pace.skcap"
    first, second = PtyPair(), PtyPair()
    reader = PtyReader(first.master)
    rt = ["--realtime"] if realtime else []
    out = run_serve("--port", first.path, "--record", str(rec), "--duration", str(duration_s),
                    "--quiet", *rt, timeout_s=duration_s + 120)
    reader.stop()
    assert out.returncode == 0, out.stderr
    reader = PtyReader(second.master)
    with SerialTransport(second.path) as link:
        figures = replay_pace(rec, link, realtime, "serial")
    reader.stop()
    print(f"\n[pace] UDP: serve --udp --record, {duration_s:g} s; replay onto a second port")
    rec = tmp / "pace_udp.skcap"
    with UdpTransport("127.0.0.1", 0, listen=True) as host:
        port = host.port
        out = run_serve("--udp", f"127.0.0.1:{port}", "--record", str(rec), "--duration",
                        str(duration_s), "--quiet", *rt, timeout_s=duration_s + 120)
        assert out.returncode == 0, out.stderr
        with UdpTransport("127.0.0.1", port) as link:
            figures += replay_pace(rec, link, realtime, "UDP")
    return figures


# -- a long stream ------------------------------------------------------------------------
def synthetic_ticks(n_events: int, seed: int = 0) -> Iterator[tuple[int, np.ndarray,
                                                                    protocols.Marker | None]]:
    """(end of the flush µs, its events, a marker or None) for ``n_events`` events."""
    rng = np.random.default_rng(seed)
    steps = np.repeat(np.arange(10), EVENTS_PER_MS // 10)
    for ms in range(n_events // EVENTS_PER_MS):
        addr = np.concatenate([np.sort(rng.choice(protocols.N_CHANNELS, EVENTS_PER_MS // 10,
                                                  replace=False)) for _ in range(10)])
        ev = make_events(ms * 1000 + steps * 100, addr)
        marker = None
        if ms % MARKER_EVERY_MS == 0:
            phase = (protocols.MarkerPhase.ONSET if ms % (2 * MARKER_EVERY_MS) == 0
                     else protocols.MarkerPhase.END)
            marker = protocols.Marker(t_us=ms * 1000, stimulus_id=(ms // 1000) % 9,
                                      phase=phase)
        yield (ms + 1) * 1000, ev, marker


class NullLink(Transport[Any]):
    """Takes everything at once (the link's speed is not what is measured)."""

    def __init__(self, kind: str) -> None:
        self.kind = kind

    @property
    def name(self) -> str:
        return "null"

    def send(self, payload: Any, timeout: float | None = None) -> int:
        return len(payload)

    def recv(self, timeout: float | None = None) -> Any:
        return self.empty()

    def wire_seconds(self, payload: Any) -> float:
        return 0.0

    def empty(self) -> Any:
        return [] if self.kind == "can" else b""

    def shutdown(self) -> None:
        pass


def part_record(n_events: int, tmp: Path) -> list[dict[str, Any]]:
    figures = []
    for suffix, kind in ((".skcap", "serial"), (".blf", "can")):
        path = tmp / f"long{suffix}"
        enc: Any = (protocols.CanEncoder(fd=True) if kind == "can"
                    else protocols.SerialEncoder())
        t0 = time.perf_counter()
        with link_recorder(path, kind, 3, 100) as recorder:
            link = RecordingTransport(NullLink(kind), recorder, lambda: 0)
            start = peak = 0.0
            for k, (t_end, ev, marker) in enumerate(synthetic_ticks(n_events)):
                link.send(enc.events(ev, t_end))
                if marker is not None:
                    link.send(enc.marker(marker))
                if k == WARM_TICKS:  # the codec's kernels are loaded by now
                    start = peak = rss_mb()
                elif k % 2000 == 0:
                    peak = max(peak, rss_mb())
            peak = max(peak, rss_mb())
        wall = time.perf_counter() - t0
        units = "CAN FD frames" if kind == "can" else "serial packets"
        print(f"\n[record] {n_events:,} events into {suffix} ({units}), "
              f"{recorder.units:,} units, "
              f"{path.stat().st_size / 1e6:.1f} MB file, {wall:.1f} s: VmRSS {start:.1f} MB "
              f"at the start, peak {peak:.1f} MB (growth {peak - start:+.1f} MB), "
              f"{rss_mb():.1f} MB after; {load_average()}")
        figures += [figure(f"{suffix}: VmRSS growth over {n_events:,} events",
                           round(peak - start, 1), "MB", "< 50"),
                    figure(f"{suffix}: file", round(path.stat().st_size / 1e6, 1), "MB"),
                    figure(f"{suffix}: wall", round(wall, 1), "s")]
        path.unlink()
    return figures


def part_session(n_events: int, tmp: Path) -> list[dict[str, Any]]:
    """listen --record's recorder alone: the decoded events of a long stream into a
    SessionRecorder, then the .npz; memory from the first flush to the end of the save."""
    rec = SessionRecorder(tmp)
    start = peak = 0.0
    t0 = time.perf_counter()
    for k, (_, ev, marker) in enumerate(synthetic_ticks(n_events)):
        rec.on_events(ev, 0.0)
        if marker is not None:
            rec.on_marker(marker)
        if k == WARM_TICKS:
            start = peak = rss_mb()
        elif k % 2000 == 0:
            peak = max(peak, rss_mb())
    fed = time.perf_counter() - t0
    out = rec.save(tmp / "session.npz")
    peak = max(peak, rss_mb("self", "VmHWM"))
    rec.close()
    print(f"\n[session] {n_events:,} events into listen --record's SessionRecorder in "
          f"{fed:.1f} s, saved to .npz in {time.perf_counter() - t0 - fed:.1f} s "
          f"({out.stat().st_size / 1e6:.1f} MB): VmRSS {start:.1f} MB at the start, peak "
          f"{peak:.1f} MB (VmHWM, the save included; growth {peak - start:+.1f} MB); "
          f"{load_average()}")
    figures = [figure(f"VmRSS growth over {n_events:,} events, the save included",
                      round(peak - start, 1), "MB", "< 50"),
               figure(".npz file", round(out.stat().st_size / 1e6, 1), "MB")]
    out.unlink()
    return figures


def part_listen(n_events: int, tmp: Path, record: bool = True,
                arena_max: int | None = None) -> list[dict[str, Any]]:
    model = tmp / "decoder.npz"
    subprocess.run([sys.executable, "-m", "skinhil", "train", "--out", str(model), "--reps",
                    "8", "--snr-db", "inf", "--no-progress"], cwd=RUN_DIR, env=serve_env(),
                   check=True, capture_output=True)
    out = tmp / "session.npz"
    pair = PtyPair()
    proc = subprocess.Popen([sys.executable, "-m", "skinhil", "listen", "--port", pair.path,
                             "--model", str(model), "--json"]
                            + (["--record", str(out)] if record else []),
                            cwd=RUN_DIR, env={**serve_env(), **(
                                {} if arena_max is None
                                else {"MALLOC_ARENA_MAX": str(arena_max)})},
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    samples: list[tuple[float, float]] = []
    anon: list[float] = []
    done = threading.Event()

    def sample() -> None:
        while not done.is_set():
            try:
                samples.append((time.monotonic(), rss_mb(proc.pid)))
                anon.append(rss_mb(proc.pid, "RssAnon"))
            except OSError:
                return
            time.sleep(0.2)

    time.sleep(8.0)  # listen loads its model and compiles / loads its kernels
    base = rss_mb(proc.pid)
    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    t0 = time.monotonic()
    enc = protocols.SerialEncoder()
    for t_end, ev, marker in synthetic_ticks(n_events):
        data = enc.events(ev, t_end) + (enc.marker(marker) if marker is not None else b"")
        view = memoryview(data)
        while view:
            n = os.write(pair.master, view)
            view = view[n:]
    while True:  # until listen has read everything
        pending = fcntl.ioctl(pair.slave, termios.FIONREAD, b"\0\0\0\0")
        if int.from_bytes(pending, "little") == 0:
            break
        time.sleep(0.1)
    fed = time.monotonic() - t0
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=600)
    done.set()
    sampler.join()
    pair.close()
    n_saved = 0
    if record:
        with np.load(out) as z:
            n_saved = z["events"].shape[0]
    peak = max(m for _, m in samples)
    at = [m for t, m in samples if t >= t0 + 0.1 * fed][:1] + \
        [m for t, m in samples if t >= t0 + 0.5 * fed][:1] + \
        [m for t, m in samples if t <= t0 + fed][-1:]
    after = [f"{t - t0 - fed:.1f} s {m:.0f} ({a:.0f})"
             for (t, m), a in zip(samples, anon, strict=False) if t > t0 + fed]
    warm = [m for t, m in samples if t >= t0 + 0.01 * fed][0]
    print("  VmRSS (RssAnon) after the stream (s after, MB):", ", ".join(after))
    print(f"\n[listen] {n_events:,} events fed in {fed:.1f} s to listen "
          f"{'--record .npz' if record else '(no --record: the control)'}"
          f"{'' if arena_max is None else f' with MALLOC_ARENA_MAX={arena_max}'} "
          f"(exit {proc.returncode}); {n_saved:,} events in the file "
          f"({out.stat().st_size / 1e6 if record else 0:.1f} MB); listen VmRSS {base:.1f} MB "
          "before the "
          f"stream, {' / '.join(f'{m:.1f}' for m in at)} MB at 10 % / 50 % / the end of the "
          f"stream, peak {peak:.1f} MB including the save: growth {peak - base:+.1f} MB from "
          f"before the stream, {peak - warm:+.1f} MB from 1 % into it ({warm:.1f} MB: the "
          "receiver's kernels loaded by the first data); "
          f"{load_average()}")
    if proc.returncode != 0:
        print(err[-2000:])
    return [figure("exit status", proc.returncode, "status", "0"),
            figure("events in the file", n_saved, "events", f"{n_events:,}" if record else ""),
            figure("VmRSS growth from before the stream", round(peak - base, 1), "MB", "< 50"),
            figure("VmRSS growth from 1 % into the stream", round(peak - warm, 1), "MB")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--parts", default="pace,record,session,listen,listen-control")
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--events", type=int, default=10_000_000)
    ap.add_argument("--malloc-arena-max", type=int, default=None, metavar="N",
                    help="listen: run it with MALLOC_ARENA_MAX=N (glibc's per-thread heaps "
                         "otherwise make its resident memory vary by ~100 MB from run to run)")
    ap.add_argument("--realtime", action="store_true",
                    help="pace: the board and the replay with real-time scheduling (root)")
    ap.add_argument("--smoke", action="store_true",
                    help="pace, record, session: 1 s and 20,000 events: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.parts, args.duration, args.events = "pace,record,session", 1.0, 20_000
    print(describe())
    print(load_average())
    parts = args.parts.split(",")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if "pace" in parts:
            publish(args, "record_replay_pace", f"Replay pace: {args.duration:g} s of a live "
                    "board recorded and replayed", part_pace(args.duration, tmp, args.realtime))
        if "record" in parts:
            publish(args, "record_replay_record", f"serve --record's recording path: "
                    f"{args.events:,} events", part_record(args.events, tmp))
        if "session" in parts:
            publish(args, "record_replay_session", f"listen --record's session recorder: "
                    f"{args.events:,} events", part_session(args.events, tmp))
        arena = ("" if args.malloc_arena_max is None
                 else f", MALLOC_ARENA_MAX={args.malloc_arena_max}")
        if "listen" in parts:
            publish(args, "record_replay_listen", f"listen --record as a process: "
                    f"{args.events:,} events{arena}",
                    part_listen(args.events, tmp, arena_max=args.malloc_arena_max))
        if "listen-control" in parts:
            publish(args, "record_replay_listen_control", f"listen without --record (the "
                    f"control): {args.events:,} events{arena}",
                    part_listen(args.events, tmp, record=False,
                                arena_max=args.malloc_arena_max))


if __name__ == "__main__":
    main()
