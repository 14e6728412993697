"""``skinhil demo --task grasp``: the board holds an object through a run of lifts; the
reference grip controller on the other end of a pty grips it from the spikes; the scores.

The board runs as ``skinhil serve --grasp LIFTS`` in a subprocess; the controller
(:mod:`skinhil.receiver.grip_reflex`, its load readout fitted on first use at the demo's SNR
and cached beside the demo's model) reads the pty master and sends GRIPs; ``--controller
off`` sends none, so the hand keeps its constant low grip. The board scores every lift
(docs: Grasp) into its score file, which the demo prints. With ``--view`` the live view
shows the stream and plots the held object's truth, which the board appends to a file of the
demo's (``serve --grasp-truth``: the operator's side channel, not the decoder's link).
"""

from __future__ import annotations

import argparse
import json
import os
import threading
import time
from pathlib import Path
from typing import Any

from protocols.kernel_cache import source_hash
from skinhil.cli import signals
from skinhil.cli.demo_cache import board_warming, cache_dir
from skinhil.cli.lab_outputs import LabOutputs, check_lab_outputs
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, spring_count
from skinhil.plant import GraspParams, lifts_duration_s
from skinhil.plant.report import grasp_text
from skinhil.plant.truth_file import HeldTruthReader
from skinhil.receiver.grip_loop import GripLoop
from skinhil.receiver.grip_reflex import GripController, LoadReadout, SlipReflex
from skinhil.receiver.grip_training import SUITE_TRAINING_GRIPS_N, TrainingLifts, fit_readout
from skinhil.receiver.receiver import ReceiverListener
from skinhil.receiver.session import run_against_board, serve_command
from skinhil.temp_folders import TempFolder
from skinhil.transports import PtyMasterTransport
from skinhil.view.grasp_trace import GraspTrace

TAIL_PERIOD_S = 0.05
"""Seconds between reads of the board's truth file for the live view."""


READOUT_CASE = "tactile-v1:grasp"
"""The suite case whose lifts the reference controller's readout is fitted on."""
READOUT_SEEDS = (1, 2, 3)
"""Its training seeds the readout is fitted on (none an evaluation seed)."""


def readout_training_runs() -> tuple[TrainingLifts, ...]:
    """The lifts of :data:`READOUT_CASE` at :data:`READOUT_SEEDS`: light fragile and heavy
    sturdy objects, never those ``bench --suite`` draws."""
    from skinhil.suites import suite, suite_trials

    name = READOUT_CASE.split(":")[0]
    out: list[TrainingLifts] = []
    for seed in READOUT_SEEDS:
        if seed not in suite(name).training_seeds:
            raise ConfigError(f"seed {seed} is not a training seed of {name}")
        trials = suite_trials(READOUT_CASE, seed)
        scene, params = trials.scenario.scene, trials.grasp
        if scene is None or params is None:
            raise ConfigError(f"{READOUT_CASE} holds no object to fit a grip readout on")
        out.append((scene, trials.duration_s, params))
    return tuple(out)


def cached_readout(snr_db: float, baud: int, seed: int) -> Path:
    """The grip controller's load readout for ``snr_db``, fitted now if missing (while a
    board at ``baud`` and ``seed`` warms its kernels in another process)."""
    path = cache_dir() / f"grip-readout-{snr_db:g}dB-{source_hash()}.npz"
    if path.exists():
        return path
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"the demo's cache '{path.parent}' cannot be written "
                          f"({exc.strerror or exc}) — set XDG_CACHE_HOME to a writable "
                          "folder") from None
    print(f"fitting the grip controller's load readout at {snr_db:g} dB on simulated lifts "
          f"(first use; cached in {path.parent})", flush=True)
    with board_warming(baud, snr_db, seed):
        readout = fit_readout(snr_db, runs=readout_training_runs(),
                              grips_n=SUITE_TRAINING_GRIPS_N)
    readout.save(path)
    for old in path.parent.glob(f"grip-readout-{snr_db:g}dB-*.npz"):
        if old != path:
            old.unlink(missing_ok=True)
    return path


class TruthTail:
    """Hands the board's held-object truth (its ``--grasp-truth`` file) to the live view's
    grasp panel every :data:`TAIL_PERIOD_S`, on a thread, until :meth:`stop`."""

    def __init__(self, reader: HeldTruthReader, trace: GraspTrace) -> None:
        self.reader, self.trace = reader, trace
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="skinhil-grasp-truth",
                                        daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(TAIL_PERIOD_S):
            self.trace.add(self.reader.read())

    def stop(self) -> None:
        """Read the rest (the board has ended), close the last lift, stop the thread."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.trace.add(self.reader.read())
        self.trace.finish()


def print_lifts(scores: dict[str, Any]) -> None:
    """One line per lift."""
    print(f"{'lift':>4}  {'held':>5}  {'slip onset':>10}  {'reaction':>9}  {'slid':>8}  "
          f"{'peak grip':>9}  {'economy':>7}")
    for t in scores.get("trials", []):
        def ms(v: float | None) -> str:
            return "-" if v is None else f"{v:.0f} ms"
        econ = "-" if t["grip_economy"] is None else f"{t['grip_economy']:.2f}"
        print(f"{t['lift']:>4}  {'yes' if t['held'] else 'DROP':>5}  "
              f"{ms(t['slip_onset_ms']):>10}  {ms(t['reaction_latency_ms']):>9}  "
              f"{t['slip_distance_mm']:>5.2f} mm  {t['peak_grip_n']:>7.2f} N  {econ:>7}")


def run(args: argparse.Namespace) -> dict[str, Any]:
    """The grasp demo (module docstring); its result (``demo --json``'s object)."""
    given = [opt for opt, dest in (("--lsl", "lsl"), ("--psp-sensors", "psp_sensors"),
                                   ("--model", "model"))
             if getattr(args, dest, None) is not None]
    if given:
        raise ConfigError(f"{', '.join(given)} go{'es' if len(given) == 1 else ''} with the "
                          "directions demo: the grasp demo has no stimulus decoder or "
                          "LSL outlets — drop it, or leave out --task grasp")
    check_lab_outputs(args, PAPER_SIZE)
    t_start = time.monotonic()
    params = GraspParams()
    listeners: list[ReceiverListener] = []
    readout = (LoadReadout.load(cached_readout(args.snr_db, args.baud, args.seed),
                                spring_count(PAPER_SIZE))
               if args.controller == "reflex" else None)
    link, slave_fd = PtyMasterTransport.open_pair(args.baud)
    controller = None
    if readout is not None:
        controller = GripController(link, SlipReflex(readout))
        listeners.append(controller)
    score_dir = TempFolder("demo")
    score = score_dir.path / "score.json"
    truth = score_dir.path / "truth.bin"
    duration_s = lifts_duration_s(params, args.lifts)
    view_args = ["--grasp-truth", str(truth)] if args.view is not None else []
    cmd = serve_command(["--port", link.slave_path, "--baud", str(args.baud), "--grasp",
                         str(args.lifts), "--score", str(score), *view_args], duration_s,
                        args.snr_db, args.seed)
    print(f"board: {' '.join(cmd[1:])}\ncontroller: {args.controller} on {link.name}; "
          f"object {params.mass_kg * 1e3:g} g (load {params.weight_n:.2f} N, pull "
          f"{params.pull_n:g} N), slip ratio {params.slip_ratio:.2f}, hand's low grip "
          f"{params.initial_grip_n:g} N", flush=True)
    loop = GripLoop(link, listeners)
    outputs = LabOutputs(args, {}, PAPER_SIZE, "demo") if args.view is not None else None
    trace = GraspTrace()
    feed = outputs.view_feed(0, loop, grasp=trace) if outputs is not None else None
    if feed is not None:
        listeners.append(feed)
    tail = TruthTail(HeldTruthReader(truth), trace) if feed is not None else None
    try:
        with signals.stop_event(lambda: "stopping: the board ends the lift under way and "
                                        "scores the lifts it played; Ctrl-C again stops at "
                                        "once") as stop:
            status, out, err = run_against_board(loop, cmd, stop=stop)
    finally:
        link.shutdown()
        os.close(slave_fd)
        if tail is not None:
            tail.stop()
        if outputs is not None:
            outputs.close()
    with score_dir:
        board_score = json.loads(score.read_text(encoding="utf-8")) if score.exists() else None
    if status not in (0, signals.exit_status(0)) or board_score is None:
        raise ConfigError(f"the board stopped with status {status}: "
                          f"{err.strip().splitlines()[-1] if err.strip() else 'no score'}")
    scores = board_score["grasp"]
    c = controller.as_dict() if controller is not None else None
    wall_s = time.monotonic() - t_start
    if not args.json:
        if not args.quiet:
            print_lifts(scores)
        print(grasp_text(scores))
        if c is not None:
            print(f"controller: {c['sent']} GRIPs sent ({c['acked']} ACK, {c['nacked']} "
                  f"NACK, {c['unanswered']} unanswered), {c['unsent']} not sent (no room on "
                  "the link)")
        print(f"demo: {args.lifts} lifts at {args.snr_db:g} dB, controller "
              f"{args.controller}, {wall_s:.1f} s wall in all", flush=True)
    return {"task": "grasp", "lifts": args.lifts, "snr_db": args.snr_db, "seed": args.seed,
            "controller": args.controller, "grips": c, "board_score": board_score,
            "wall_s": round(wall_s, 3)}
