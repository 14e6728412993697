"""``skinhil simulate``: run the skin and its neurons offline and save forces and spikes."""

from __future__ import annotations

import argparse
import datetime
import json
import math
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from skinhil.cli import signals
from skinhil.cli.conventions import add_json_option, print_json
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.nwb_options import add_nwb_args, nwb_metadata
from skinhil.cli.options import (
    SCHEDULE_HELP,
    add_model_options,
    model_from_args,
    noise_from_args,
    read_scenario,
)
from skinhil.cli.values import check_memory, real
from skinhil.errors import ConfigError
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import STRAIN_BOUND
from skinhil.model.stimuli import Schedule, ScheduledStimulus, builtin_catalog
from skinhil.model.strain import max_strain
from skinhil.nwb import require_pynwb, write_simulation
from skinhil.output_files import atomic_path, check_output_path
from skinhil.world import TouchSensor
from skinhil.world.scenario_file import Scenario
from skinhil.world.truth import TRUTH_DTYPE, TRUTH_PERIOD_S

MAX_DURATION_S = 1e6
"""Longest simulation (s of model time); memory is estimated before any is allocated."""
OUT_SUFFIXES = (".npz", ".nwb")
"""What ``--out`` may end in: the format it selects."""
BLOCK_S = 0.05
"""Simulated seconds per progress-bar update."""


SIMULATE_SNR_DB = math.inf
"""simulate's default noise: none, the paper's deterministic figures (printed on its result
line, as its seed)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "simulate", help="simulate a stimulus or schedule offline and save forces and spikes",
        description="Simulate the skin and its neurons offline and write an .npz file with "
                    "spring forces (N, float32, n_steps x n_springs, 338 at 6x6), spike "
                    "events (t µs, addr, p), the stimulus markers and, for a scenario with "
                    "contacts, their ground truth per 1 ms tick (the truth: docs, Contact); "
                    "it prints the skin's max strain; numpy reads it with "
                    "np.load(path). An --out ending in .nwb writes an NWB file instead "
                    "(pynwb: pip install \"skinhil[nwb]\"): one unit per sensor, the "
                    "stimuli as trials, the forces as a TimeSeries.")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--stimulus", default="A", metavar="NAME",
                     help="built-in stimulus: A..E (Fig 3) or e.g. 0deg_0.5N (Fig 4) "
                          "(default: A)")
    src.add_argument("--schedule", type=Path, metavar="TOML", help=SCHEDULE_HELP)
    p.add_argument("--duration", dest="duration_s",
                   type=real(0, MAX_DURATION_S, "seconds", lo_open=True), metavar="SECONDS",
                   help="simulated time (default: until 0.25 s after the last stimulus ends)")
    p.add_argument("--out", type=Path, default=Path("run.npz"),
                   help="output file: .npz (default run.npz) or .nwb")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_option(p)
    p.add_argument("--no-forces", dest="forces", action="store_false",
                   help="do not keep the spring forces (n_steps x n_springs floats: 14 GB for "
                        "10 s of a 48x48 skin); the file then holds an empty forces_n")
    add_model_options(p, snr_default=SIMULATE_SNR_DB)
    add_nwb_args(p)


def _scenario(args: argparse.Namespace) -> Scenario:
    if args.schedule is not None:
        return read_scenario(args.schedule, args.size)
    catalog = builtin_catalog(args.size)
    if args.stimulus not in catalog:
        raise ConfigError(f"unknown stimulus {args.stimulus!r}; choose one of "
                          f"{', '.join(catalog)} or give --schedule FILE")
    sid, stim = catalog[args.stimulus]
    return Scenario(Schedule((ScheduledStimulus(0.0, stim, sid),)), None)


def run(args: argparse.Namespace) -> int:
    out = check_output_path(args.out, OUT_SUFFIXES)
    nwb_meta = nwb_metadata(args, out.suffix.lower() == ".nwb")
    if out.suffix.lower() == ".nwb":
        require_pynwb()
    scenario = _scenario(args)
    schedule, scene = scenario.schedule, scenario.scene
    duration = args.duration_s if args.duration_s is not None else scenario.duration_s + 0.25
    model = model_from_args(args)
    model.check_schedule(schedule)  # a force on a fixed mass would be lost without a word
    n_steps = int(round(duration / args.dt_s))
    if args.forces:
        check_memory(n_steps * model.n_springs * 4, f"the spring forces of {duration:g} s "
                     f"at --dt {args.dt_s:g} ({n_steps} steps x {model.n_springs} springs)",
                     "give --no-forces, a shorter --duration or a larger --dt")
    announce_cold_cache("simulate")
    sensor = SkinSensor(model, args.dt_s, args.snr_db, args.seed,
                        noise=noise_from_args(args), threads=args.threads,
                        state_forces=scene is not None)
    touch = TouchSensor(sensor, scene) if scene is not None else None
    if touch is not None:
        touch.start(0.0)
    every = max(1, int(round(TRUTH_PERIOD_S / args.dt_s)))
    block = max(1, int(round(BLOCK_S / args.dt_s)))
    started = datetime.datetime.now(datetime.UTC)  # simulation time 0 (NWB's session start)
    forces = np.empty((n_steps if args.forces else 0, model.n_springs), dtype=np.float32)
    peak = strain = 0.0
    events = []
    truth = []
    with tqdm(total=n_steps * args.dt_s, unit="sim-s", disable=args.no_progress,
              bar_format="{l_bar}{bar}| {n:.2f}/{total:.2f} sim-s [{elapsed}<{remaining}]") as bar:
        for start in range(0, n_steps, block):
            n = min(block, n_steps - start)
            if touch is None:
                f, spikes = sensor.advance_schedule(schedule, n)
            else:
                f, spikes, raw = touch.advance_schedule(schedule, n)
                truth.append(touch.truth_at(raw, start, every))
            peak = max(peak, float(np.abs(f).max()))
            strain = max(strain, max_strain(f, model))
            if args.forces:
                forces[start:start + n] = f
            events.append(sensor.events(spikes, start))
            bar.update(n * args.dt_s)
    if not math.isfinite(peak):
        raise ConfigError(f"the spring forces overflowed (peak |force| {peak}) — give "
                          "smaller forces or a smaller --dt; nothing written")
    ev = np.concatenate(events)
    truth_rec = np.concatenate(truth) if truth else np.zeros(0, dtype=TRUTH_DTYPE)
    markers = np.array([(e.onset_s, e.end_s, e.stimulus_id) for e in schedule.entries],
                       dtype=[("onset_s", "<f8"), ("end_s", "<f8"), ("stimulus_id", "<i4")])
    meta = {"dt_s": args.dt_s, "snr_db": args.snr_db, "noise": args.noise, "seed": args.seed,
            "mechanics": model.params.dynamics, "readout": model.params.readout,
            "size": list(model.size),
            "duration_s": n_steps * args.dt_s,
            "stimuli": [e.stimulus.name for e in schedule.entries],
            "contacts": [c.name for c in scene.contacts] if scene else [],
            "max_strain": strain,
            "params": {k: v for k, v in vars(model.params).items()}}
    if out.suffix.lower() == ".nwb":
        write_simulation(out, mesh=model.mesh, schedule=schedule, events=ev,
                         forces_n=forces if args.forces else None, dt_s=args.dt_s,
                         description=f"skinhil simulate: {json.dumps(meta)}",
                         start=started, meta=nwb_meta, truth=truth_rec,
                         n_contacts=len(scene.contacts) if scene else 0)
    else:
        # a stop waits for numpy's zip writer (whose own clean-up raises again when
        # interrupted) and then removes the partial file
        with atomic_path(out) as tmp, signals.held(), tmp.open("wb") as fh:
            np.savez_compressed(fh, forces_n=forces, events=ev, markers=markers,
                                truth=truth_rec, meta=np.array(json.dumps(meta)))
    rate = len(ev) / (n_steps * args.dt_s) / model.n_springs
    if args.json:
        print_json({"path": str(out), "steps": n_steps, "dt_s": args.dt_s,
                    "snr_db": args.snr_db, "seed": args.seed, "spikes": len(ev),
                    "rate_hz": rate, "peak_force_n": peak, "max_strain": strain,
                    "truth_records": len(truth_rec)})
        return 0
    print(f"wrote {out}: {n_steps} steps of {args.dt_s * 1e3:g} ms at {args.snr_db:g} dB, "
          f"seed {args.seed}, {len(ev)} spikes "
          f"({rate:.1f} Hz per sensor), peak |force| {peak:.3g} N, max strain "
          f"{100 * strain:.3g} % (bound {100 * STRAIN_BOUND:g} %)")
    if scene is not None:
        print(f"contact truth: {len(truth_rec)} records ({len(scene.contacts)} contact(s), "
              f"one per {every * args.dt_s * 1e3:g} ms), peak normal force "
              f"{truth_rec['normal_n'].max(initial=0.0):.3g} N, mechanics "
              f"{model.params.dynamics} ({type(sensor.stepper).__name__})")
    return 0
