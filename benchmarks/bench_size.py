"""How the board's work grows with the skin: a size benchmark (a script, not a test).

For each top-layer size (default 6x6, 16x16, 26x26, 32x32, 48x48) and the default mechanics
(``SkinParams().mechanics``, "auto": geometric up to 10x10, linear above; the ``stepper``
column says which one ran) it steps the board's loop
as :meth:`firmware_sim.board.Board.tick` does, without pacing and without a transport: per
1 ms tick of ten 0.1 ms steps, the default random schedule's forces
(:class:`skinhil.model.timeline.Timeline`), the model (mechanics and neurons, noise at ``--snr-db``,
default 10 dB), spikes to events, and the events encoded for the wire
(:class:`protocols.SerialEncoder`, wide format above 338 channels). It reports

- per step: mechanics (µs and ns per spring; the leapfrog's and the geometric mechanics'
  kernels on their input by slot, as the tick runs them),
  neurons (µs and ns per channel), each timed alone on the same forces, the two together in
  the one compiled call the tick makes (``m+n``: one call's overhead per tick, not two), and
  per tick the events and encoding (µs);
- memory: the peak of the bytes allocated (tracemalloc, kernels compiled beforehand) while
  the model, the timeline and the encoder are built and run for 20 ticks;
- the real-time factor of the whole loop (simulated s per wall s; >= 1 keeps real time),
  on one thread and, with ``--threads 2``, as ``serve --threads 2`` runs it: the mechanics
  on one thread and the neurons on another, two ticks behind
  (:class:`skinhil.model.pipeline.SensorPipeline`);
- the growth: the time per step of the whole loop against the springs, as the exponent of a
  least-squares fit of log(time) on log(springs) over the leapfrog sizes (1 = linear).

With ``--contact slide,vibrate`` it also steps the loop with a contact touching the skin
all the time (:mod:`skinhil.world`, inside the compiled step, as the board's tick does with a
scenario): a 3 mm sphere pressed with 0.3 N sliding back and forth across the skin at
20 mm/s, and a flat 1.5 mm pad 20 µm deep vibrating 8 µm at 100 Hz; it prints the loop per
step without the contact (the same empty schedule) and with it, what the contact adds (%), the
real-time factor with it, and the skin's max strain.

With ``--find-largest`` it then bisects the square sizes for the largest that keeps real
time (factor >= 1, or >= ``--min-rtf``: 1.2 leaves a fifth of each tick for the link and the
host) on one thread and on two. ``--cpu N`` runs it on core N alone.

Usage::

    python benchmarks/bench_size.py [--sizes 6,16,26,32,48] [--threads 1,2] [--snr-db 10]
                                    [--seconds 2] [--find-largest] [--min-rtf 1.0]
                                    [--clock wall|cpu] [--cpu N]
                                    [--contact slide,vibrate [--contact-only]] [--smoke]
                                    [--results-dir DIR]

``--smoke``: 6x6 and 8x8 on one thread, one 0.05 s run each (checks that the script runs).

Every figure is the best of ``--repeats`` runs (the machine is shared): the load average is
printed before and after. A brief run of the same command in a process of its own comes first
(:func:`warm_up`), so that the kernels are loaded from the disk cache as ``serve`` loads
them. ``--clock cpu`` (one thread only) times this process's CPU time instead of the wall
clock: the figures a dedicated core would give on a machine busy with other work.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import time
import tracemalloc
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(__file__))
for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
import numpy as np  # noqa: E402
from machine import describe, load_average  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

import protocols  # noqa: E402
from skinhil.model.geometry import format_size, parse_size  # noqa: E402
from skinhil.model.mechanics.geometric import GeometricMechanics, rk4_kernel  # noqa: E402
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics, leapfrog_kernel  # noqa: E402
from skinhil.model.pipeline import SensorPipeline  # noqa: E402
from skinhil.model.sensor import SkinSensor  # noqa: E402
from skinhil.model.skin import SkinModel, SkinParams  # noqa: E402
from skinhil.model.stimuli import Schedule  # noqa: E402
from skinhil.model.strain import max_strain  # noqa: E402
from skinhil.model.timeline import Timeline  # noqa: E402
from skinhil.world import Contact, Indenter, Scene, TouchSensor, Trajectory  # noqa: E402

DT_S = 1e-4
STEPS_PER_TICK = 10
CLOCK = "wall"
"""What is timed: "wall" (perf_counter) or "cpu" (this process's CPU time; one thread only)."""


@dataclass
class SizeResult:
    size: tuple[int, int]
    threads: int
    springs: int
    regime: str
    mech_us: float
    neur_us: float
    both_us: float
    """Mechanics and neurons per step in the one compiled call the tick makes (NaN where
    the tick makes two: the modal stepper, or the neurons on other threads)."""
    events_us: float
    encode_us: float
    loop_us: float
    """Per tick (10 steps) of the whole loop."""
    memory_mb: float
    events_per_s: float

    @property
    def rtf(self) -> float:
        return STEPS_PER_TICK * DT_S / (self.loop_us * 1e-6)


def _best_per_tick(fn, seconds: float, repeats: int) -> float:  # type: ignore[no-untyped-def]
    """Best over ``repeats`` runs of the mean µs per call of ``fn`` (each run at least
    ``seconds`` of wall time): wall time, or with ``CLOCK == "cpu"`` this process's CPU time
    (time.process_time: the time the machine's other work takes from it does not count)."""
    clock = time.process_time if CLOCK == "cpu" else time.perf_counter
    best = math.inf
    fn()  # compiled (or loaded from the cache) for its arguments' types before it is timed
    for _ in range(repeats):
        calls = 0
        t0 = time.perf_counter()
        c0 = clock()
        while True:
            fn()
            calls += 1
            if time.perf_counter() - t0 >= seconds:
                break
        best = min(best, (clock() - c0) / calls * 1e6)
    return best


def measure(size: tuple[int, int], threads: int, snr_db: float, seconds: float,
            repeats: int) -> SizeResult:
    warm = SkinSensor(SkinModel(SkinParams(size=(3, 3))), DT_S, snr_db=snr_db,
                      threads=max(1, threads - 1))
    warm.advance_schedule(Timeline(DT_S, size=(3, 3)).schedule, 10)  # kernels compiled first
    tracemalloc.start()
    model = SkinModel(SkinParams(size=size))
    # as the board: more than one thread pipelines the mechanics and the neurons
    sensor = SkinSensor(model, DT_S, snr_db=snr_db, seed=0, threads=max(1, threads - 1))
    pipeline = SensorPipeline(sensor) if threads > 1 else None
    timeline = Timeline(DT_S, size=size)
    encoder = protocols.SerialEncoder(step_us=int(round(DT_S * 1e6)), n_channels=model.n_springs)
    counts = {"events": 0}

    def tick() -> np.ndarray:
        first = sensor.step_index
        if pipeline is None:  # as Board.tick: the schedule's forces made in the kernel
            schedule = timeline.schedule_for(first * DT_S, (first + STEPS_PER_TICK - 1) * DT_S)
            _, spikes = sensor.advance_schedule(schedule, STEPS_PER_TICK)
        else:
            spikes, first = pipeline.advance(
                timeline.forces((first + np.arange(STEPS_PER_TICK)) * DT_S))
        events = sensor.events(spikes, first)
        encoder.events(events, int(round((first + len(spikes)) * DT_S * 1e6)))
        counts["events"] += len(events)
        return spikes

    for _ in range(20):  # compile, and let the random schedule start
        tick()
    if pipeline is not None:  # stopping tracemalloc while the worker allocates crashes CPython
        pipeline.flush()
    _, memory = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    counts["events"] = 0
    start = sensor.step_index
    loop_us = _best_per_tick(tick, seconds, repeats)
    events_per_s = counts["events"] / ((sensor.step_index - start) * DT_S)
    if pipeline is not None:
        pipeline.flush()

    # the parts, each alone on a block the loop produced while a stimulus pressed
    forces = np.zeros(1)
    while not forces.any():
        forces = timeline.forces((sensor.step_index + np.arange(STEPS_PER_TICK)) * DT_S)
        spikes = tick()
    stepper = model.stepper(DT_S)
    springs = stepper.advance(forces)
    if isinstance(stepper, LeapfrogMechanics):  # its kernel alone, as the tick runs it
        slotted, out = stepper.by_slot(forces), np.empty_like(springs)
        mech_us = _best_per_tick(lambda: leapfrog_kernel(slotted, out, DT_S,
                                                         stepper.kernel_tuple),
                                 seconds / 4, repeats)
    elif isinstance(stepper, GeometricMechanics):  # likewise
        slotted, out = stepper.by_slot(forces), np.empty_like(springs)
        mech_us = _best_per_tick(lambda: rk4_kernel(slotted, out, DT_S, stepper.kernel_tuple),
                                 seconds / 4, repeats)
    else:
        mech_us = _best_per_tick(lambda: stepper.advance(forces), seconds / 4, repeats)
    neurons = sensor.neurons
    neur_us = _best_per_tick(lambda: neurons.step_block(springs, DT_S), seconds / 4, repeats)
    both_us = math.nan  # the two in one compiled call, as the tick runs them (one thread)
    fused = sensor.stepper
    if threads == 1 and isinstance(fused, LeapfrogMechanics | GeometricMechanics):
        slotted = fused.by_slot(forces)
        both_us = _best_per_tick(lambda: sensor.run_fused(len(slotted), forces=slotted),
                                 seconds / 4, repeats)
    first = sensor.step_index
    events = sensor.events(spikes, first)
    events_us = _best_per_tick(lambda: sensor.events(spikes, first), seconds / 8, repeats)
    enc = protocols.SerialEncoder(step_us=int(round(DT_S * 1e6)), n_channels=model.n_springs)
    t_end = [int(round((first + STEPS_PER_TICK) * DT_S * 1e6))]

    def encode() -> None:
        shifted = events.copy()
        shifted["t"] += t_end[0] - int(round((first + STEPS_PER_TICK) * DT_S * 1e6))
        enc.events(shifted, t_end[0])
        t_end[0] += STEPS_PER_TICK * int(round(DT_S * 1e6))

    encode_us = _best_per_tick(encode, seconds / 8, repeats)
    regime = "geometric" if model.params.dynamics == "geometric" else model.linear_regime
    return SizeResult(size, threads, model.n_springs, regime,
                      mech_us / STEPS_PER_TICK, neur_us / STEPS_PER_TICK,
                      both_us / STEPS_PER_TICK, events_us, encode_us, loop_us, memory / 1e6,
                      events_per_s)


CONTACT_S = 600.0
"""How long the benchmark's contacts last (s of board time): longer than any run."""


def contact_scene(kind: str, size: tuple[int, int]) -> Scene:
    """The benchmark's contact ``kind`` ("slide" or "vibrate") on a skin of ``size``: a
    sliding sphere back and forth over the middle 60 % of the skin along x at 20 mm/s, or a
    vibrating pad at the centre (module docstring)."""
    depth, load = 20e-6, 0.3  # the example scenarios' touches on the default skin
    if kind == "vibrate":
        path = Trajectory(np.array([(0, 0, 0, 0), (0.02, 0, 0, depth),
                                    (CONTACT_S, 0, 0, depth)])).with_vibration(8e-6, 100.0)
        return Scene((Contact(Indenter("flat", radius_m=1.5e-3), path),))
    if kind != "slide":
        raise SystemExit(f"bench_size: unknown contact {kind!r}: give slide or vibrate")
    half = 0.3 * (size[1] - 1) * 1e-3
    crossing = 2 * half / 20e-3
    keys = [(0.0, -half, 0.0, 0.0), (0.02, -half, 0.0, load)]
    t, x = 0.02, -half
    while t < CONTACT_S:
        t, x = t + crossing, -x
        keys.append((t, x, 0.0, load))
    return Scene((Contact(Indenter("sphere", radius_m=3e-3),
                          Trajectory(np.array(keys), normal="force")),))


@dataclass
class ContactResult:
    size: tuple[int, int]
    kind: str
    stepper: str
    plain_us: float
    """Loop per step without the contact (µs)."""
    touch_us: float
    """Loop per step with it (µs)."""
    strain: float

    @property
    def added(self) -> float:
        return self.touch_us / self.plain_us - 1.0


def measure_contact(size: tuple[int, int], kind: str, snr_db: float, seconds: float,
                    repeats: int) -> ContactResult:
    """The board's loop (one thread) on an empty schedule, without and with contact
    ``kind`` (:func:`contact_scene`), per step."""
    model = SkinModel(SkinParams(size=size))
    encoders = [protocols.SerialEncoder(step_us=int(round(DT_S * 1e6)),
                                        n_channels=model.n_springs) for _ in range(2)]
    schedule = Schedule(())
    plain = SkinSensor(model, DT_S, snr_db=snr_db, seed=0, state_forces=True)
    touch = TouchSensor(SkinSensor(model, DT_S, snr_db=snr_db, seed=0, state_forces=True),
                        contact_scene(kind, size))
    touch.start(0.0)
    strain = [0.0]

    def plain_tick() -> None:
        first = plain.step_index
        _, spikes = plain.advance_schedule(schedule, STEPS_PER_TICK)
        encoders[0].events(plain.events(spikes, first), (first + STEPS_PER_TICK) * 100)

    def touch_tick() -> None:
        first = touch.sensor.step_index
        _, spikes, _ = touch.advance_schedule(schedule, STEPS_PER_TICK)
        encoders[1].events(touch.sensor.events(spikes, first),
                           (first + STEPS_PER_TICK) * 100)

    for _ in range(50):  # compile, and press in
        plain_tick()
        touch_tick()
    for _ in range(500):
        first = touch.sensor.step_index
        springs, spikes, _ = touch.advance_schedule(schedule, STEPS_PER_TICK)
        encoders[1].events(touch.sensor.events(spikes, first), (first + STEPS_PER_TICK) * 100)
        strain[0] = max(strain[0], max_strain(springs, model))
    plain_us = touch_us = math.inf
    for _ in range(repeats):  # in turns, so that a burst of the machine's load hits both
        plain_us = min(plain_us, _best_per_tick(plain_tick, seconds, 1) / STEPS_PER_TICK)
        touch_us = min(touch_us, _best_per_tick(touch_tick, seconds, 1) / STEPS_PER_TICK)
    return ContactResult(size, kind, type(plain.stepper).__name__.replace("Mechanics", ""),
                         plain_us, touch_us, strain[0])


def _row(r: SizeResult) -> str:
    return (f"{format_size(r.size):>6} {r.threads:>2} {r.springs:>7} {r.regime:>9} "
            f"{r.mech_us:8.1f} {1e3 * r.mech_us / r.springs:6.2f} "
            f"{r.neur_us:8.1f} {1e3 * r.neur_us / r.springs:6.2f} {r.both_us:7.1f} "
            f"{r.events_us:7.1f} {r.encode_us:7.1f} {r.loop_us / STEPS_PER_TICK:8.1f} "
            f"{1e3 * r.loop_us / STEPS_PER_TICK / r.springs:6.2f} {r.memory_mb:7.1f} "
            f"{r.events_per_s / 1e3:8.1f} {r.rtf:6.2f}")


WHOLE_HAND = (34, 34)
"""The size issue 46's targets are set at (a whole hand: 17,866 sensors)."""
REAL_TIME_SENSORS = 10_000
"""Sensors from which one core is held to real time."""


def size_figures(r: SizeResult) -> list[dict[str, object]]:
    """The figures of one size on ``r.threads`` threads, with the targets set for it: at
    34x34 on one thread a real-time factor >= 1.6 and neurons <= 1.5 ns per channel-step
    (issue 46); from 10,000 sensors on one thread real time."""
    k = f"{r.threads} thread{'s' if r.threads > 1 else ''}"
    one = r.threads == 1
    hand = one and r.size == WHOLE_HAND
    rtf_target = "≥ 1.6" if hand else "≥ 1" if one and r.springs >= REAL_TIME_SENSORS else ""
    step = r.loop_us / STEPS_PER_TICK
    return [figure(f"{k}: real-time factor of the loop", round(r.rtf, 2), "x real time",
                   rtf_target),
            figure(f"{k}: loop per step", round(step, 1), "µs"),
            figure(f"{k}: mechanics per spring-step", round(1e3 * r.mech_us / r.springs, 2),
                   "ns", ""),
            figure(f"{k}: neurons per channel-step", round(1e3 * r.neur_us / r.springs, 2),
                   "ns", "≤ 1.5" if hand else ""),
            figure(f"{k}: events per tick", round(r.events_us, 1), "µs"),
            figure(f"{k}: encoding per tick", round(r.encode_us, 1), "µs"),
            figure(f"{k}: model memory allocated", round(r.memory_mb, 1), "MB"),
            figure(f"{k}: events generated", round(r.events_per_s), "events/s")]


HEADER = (f"{'size':>6} {'th':>2} {'springs':>7} {'stepper':>9} "
          f"{'mech µs':>8} {'ns/sp':>6} {'neur µs':>8} {'ns/ch':>6} {'m+n µs':>7} "
          f"{'ev µs':>7} {'enc µs':>7} {'loop µs':>8} {'ns/sp':>6} {'mem MB':>7} "
          f"{'kev/s':>8} {'RTF':>6}\n"
          "(mech, neur, m+n and loop per 0.1 ms step, m+n the two in the tick's one compiled "
          "call; ev and enc per 1 ms tick; mem: model bytes allocated, tracemalloc; RTF: "
          "real-time factor of the loop)")


def growth_exponent(results: list[SizeResult]) -> float:
    """Slope of log(loop time per step) on log(springs) over the leapfrog sizes."""
    pts = [(math.log(r.springs), math.log(r.loop_us)) for r in results
           if r.regime == "leapfrog"]
    if len(pts) < 2:
        return math.nan
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def find_largest(threads: int, snr_db: float, seconds: float, repeats: int,
                 lo: int, hi: int, min_rtf: float = 1.0) -> tuple[int, SizeResult | None]:
    """Largest square side in [lo, hi] whose loop runs at ``min_rtf`` times real time or
    faster (lo is assumed to)."""
    best: SizeResult | None = None
    while lo < hi:
        mid = (lo + hi + 1) // 2
        r = measure((mid, mid), threads, snr_db, seconds, repeats)
        print(_row(r), flush=True)
        if r.rtf >= min_rtf:
            lo, best = mid, r
        else:
            hi = mid - 1
    return lo, best


WARM_UP_ENV = "SKINHIL_BENCH_SIZE_WARM_UP"
"""Set in the warm-up run (:func:`warm_up`), which must not start one of its own."""


def warm_up(argv: list[str]) -> None:
    """Run this benchmark once briefly (0.01 s per timing, one repeat) in a process of its
    own, so that the kernels this run uses come from the disk cache, as they do for
    ``serve`` after its first run: a process that compiles its kernels itself runs the loop
    slower than ``serve`` does (docs/benchmarks-log.md, "Performance"). The warm-up writes
    no result."""
    t0 = time.monotonic()
    subprocess.run([sys.executable, __file__, *argv, "--seconds", "0.01", "--repeats", "1",
                    "--no-save"],
                   env={**os.environ, WARM_UP_ENV: "1"}, stdout=subprocess.DEVNULL,
                   check=True)
    print(f"kernels compiled and cached by a warm-up run first ({time.monotonic() - t0:.0f} s)",
          flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="6,16,26,32,48",
                    help="top-layer sizes, comma-separated (N or RxC)")
    ap.add_argument("--threads", default="1,2", help="thread counts, comma-separated")
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seconds", type=float, default=2.0, help="wall s per timed run")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--find-largest", action="store_true")
    ap.add_argument("--min-rtf", type=float, default=1.0,
                    help="--find-largest: the real-time factor a size must reach (1.0)")
    ap.add_argument("--cpu", type=int, default=None, help="run on this core alone")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="time wall clock, or this process's CPU time (one thread: what a "
                         "dedicated core would take, whatever else the machine runs)")
    ap.add_argument("--contact", default="",
                    help="contact scenarios to time, comma-separated: slide, vibrate "
                         "(module docstring)")
    ap.add_argument("--contact-only", action="store_true",
                    help="with --contact: only the contact table")
    ap.add_argument("--smoke", action="store_true",
                    help="6x6 and 8x8, one thread, one 0.05 s run each: the script runs")
    add_arguments(ap)
    args = ap.parse_args()
    if args.smoke:
        args.sizes, args.threads, args.seconds, args.repeats = "6,8", "1", 0.05, 1
    elif not os.environ.get(WARM_UP_ENV):
        warm_up(sys.argv[1:])
    if args.cpu is not None:
        os.sched_setaffinity(0, {args.cpu})  # before any thread starts: all on that core
    global CLOCK
    CLOCK = args.clock
    sizes = [parse_size(s) for s in args.sizes.split(",")]
    thread_counts = [int(t) for t in args.threads.split(",")]
    print(describe())
    if args.clock == "cpu" and max(thread_counts) > 1:
        ap.error("--clock cpu times one thread: CPU time of several threads is not wall time")
    how = (f"{args.snr_db:g} dB, {args.clock} time, best of {args.repeats} runs of "
           f">= {args.seconds:g} s{'' if args.cpu is None else f', core {args.cpu}'}")
    print(f"noise {args.snr_db:g} dB (diffusion), dt 0.1 ms, 1 ms ticks; {args.clock} time, "
          f"best of {args.repeats} runs of >= {args.seconds:g} s; {load_average()}", flush=True)
    if args.contact:
        print(f"{'size':>6} {'contact':>8} {'stepper':>9} {'plain µs':>9} {'touch µs':>9} "
              f"{'added':>7} {'RTF':>6} {'strain':>7}\n(loop per 0.1 ms step on one thread, "
              "the empty schedule without and with the contact; RTF with it)", flush=True)
        for size in sizes:
            for kind in args.contact.split(","):
                c = measure_contact(size, kind, args.snr_db, args.seconds, args.repeats)
                print(f"{format_size(size):>6} {kind:>8} {c.stepper:>9} {c.plain_us:9.2f} "
                      f"{c.touch_us:9.2f} {100 * c.added:6.1f}% "
                      f"{DT_S * 1e6 / c.touch_us:6.2f} {100 * c.strain:6.1f}%", flush=True)
                publish(args, f"size_contact_{kind}_{format_size(size)}",
                        f"Board loop with a {kind} contact: {format_size(size)} ({how})", [
                            figure("loop per step without the contact", round(c.plain_us, 2),
                                   "µs"),
                            figure("loop per step with it", round(c.touch_us, 2), "µs"),
                            figure("added by the contact", round(100 * c.added, 1), "%"),
                            figure("real-time factor with it", round(DT_S * 1e6 / c.touch_us, 2),
                                   "x real time"),
                            figure("max strain", round(100 * c.strain, 1), "%")])
        if args.contact_only:
            print(load_average())
            return
    print(HEADER, flush=True)
    by_size: dict[tuple[int, int], list[dict[str, object]]] = {size: [] for size in sizes}
    largest: list[dict[str, object]] = []
    springs: dict[tuple[int, int], int] = {}
    for threads in thread_counts:
        results = []
        for size in sizes:
            r = measure(size, threads, args.snr_db, args.seconds, args.repeats)
            results.append(r)
            print(_row(r), flush=True)
            by_size[size] += size_figures(r)
            springs[size] = r.springs
        print(f"threads {threads}: loop time per step ~ springs^{growth_exponent(results):.2f} "
              "over the leapfrog sizes (1.00 = linear)", flush=True)
        if args.find_largest:
            keeps = [r.size[0] for r in results
                     if r.rtf >= args.min_rtf and r.size[0] == r.size[1]]
            fails = [r.size[0] for r in results
                     if r.rtf < args.min_rtf and r.size[0] == r.size[1]]
            lo = max(keeps, default=6)
            hi = min([f - 1 for f in fails if f > lo], default=64)
            side, _ = find_largest(threads, args.snr_db, args.seconds, args.repeats, lo, hi,
                                   args.min_rtf)
            print(f"threads {threads}: largest square skin at >= {args.min_rtf:g}x real "
                  f"time: {side}x{side} "
                  f"({SkinModel(SkinParams(size=(side, side))).n_springs} sensors)",
                  flush=True)
            largest.append(figure(f"{threads} thread{'s' if threads > 1 else ''}: largest "
                                  f"square skin at >= {args.min_rtf:g}x real time",
                                  f"{side}x{side}", "top-layer size"))
    print(load_average())
    for size, figures in by_size.items():
        publish(args, f"size_{format_size(size)}", f"Board loop at {format_size(size)} "
                f"({springs[size]} sensors; {how})", figures)
    if largest:
        publish(args, f"size_largest_{args.min_rtf:g}", f"Largest skin at >= {args.min_rtf:g}x "
                f"real time ({how})", largest)


if __name__ == "__main__":
    main()
