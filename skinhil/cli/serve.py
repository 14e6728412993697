"""``skinhil serve``: run the emulated sensor board in real time over a serial port, CAN or
UDP; its ready and summary lines: docs, Process output."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Any

import protocols
from firmware_sim.board import Board
from firmware_sim.clock import pin_to_cores, request_realtime
from firmware_sim.config import (
    DEFAULT_RESPONSE_WINDOW_S,
    REALTIME_SPIN_S,
    BoardConfig,
    BoardSummary,
)
from firmware_sim.score import board_score, grasp_scores
from protocols.versions import wire_version
from skinhil.cli import signals
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.options import (
    DECODE_SNR_DB,
    SCHEDULE_HELP,
    add_model_options,
    noise_from_args,
    read_scenario,
)
from skinhil.cli.ready_option import add_ready_option, announce_ready, check_ready
from skinhil.cli.transport_args import (
    add_transport_args,
    describe_transport,
    open_transport,
    selected_can_fd,
    selected_link,
)
from skinhil.cli.values import MAX_DURATION_S, MAX_REST_S, cores_value, integer, real
from skinhil.cli.written import say_written
from skinhil.errors import ConfigError
from skinhil.model.geometry import format_size, spring_count
from skinhil.model.timeline import Timeline
from skinhil.output_files import atomic_path, check_output_path
from skinhil.plant import GraspParams, lift_scene, lifts_duration_s
from skinhil.plant.report import grasp_text
from skinhil.plant.truth_file import HeldTruthWriter, check_truth_path
from skinhil.process_output import SUMMARY, line, ready_record
from skinhil.recording import (
    CAPTURE_SUFFIX,
    RecordingTransport,
    Replayer,
    ReplaySummary,
    check_link_fits,
    link_recorder,
    open_recording,
)
from skinhil.scoring import DecisionScoreboard, scoreboard_text, truth_lines
from skinhil.scoring.score_file import score_record
from skinhil.suites import case_ref, suite_trials
from skinhil.suites.announcement import announcement
from skinhil.world.scene import MAX_CONTACTS as MAX_LIFTS

LIVE_WINDOW_TICKS = 1000
"""The live status's lateness p99 is over this many most recent ticks (its max is over the
whole run): percentiles over the whole history inside the tick loop would stall it."""
MAX_BOARD_ID = 15
"""Largest board id (the CAN layout reserves 4 bits for it)."""
MAX_TICK_S = 1.0
"""Longest publish tick (s)."""
MAX_FIFO_EVENTS = 1 << 22
"""Largest event FIFO (4,194,304 events, 48 MB)."""
MAX_RESPONSE_WINDOW_S = 3600.0
"""Longest response window (s) of the decoder under test's scoreboard."""
STATUS_PERIOD_RANGE_S = (1e-3, 60.0)
"""Status/heartbeat periods (s) the board takes."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """``serve``'s parser: its options in sections (link, what the board plays, board,
    model, scoring, recording and truth, real time, output), so ``serve --help`` reads by
    mode."""
    p = subparsers.add_parser(
        "serve", help="run the emulated sensor board in real time over serial, CAN or UDP",
        description="Run the emulated e-skin board in real time: the skin, its neurons (338 "
                    "at 6x6) and the AER link, paced to the baud rate or CAN bitrate. By default "
                    "it plays a seeded random sequence of the 9 direction conditions with rests, "
                    "each announced by a ground-truth marker. Ctrl-C stops it cleanly. A "
                    "program driving it reads its ready line and summary line "
                    "(--json, --ready-fd; docs: Process output).")
    add_transport_args(p)
    plays = p.add_argument_group(
        "stimulus and world (schedule, scenario, grasp, suite or replay)")
    src = plays.add_mutually_exclusive_group()
    src.add_argument("--schedule", type=Path, metavar="TOML",
                     help=f"play this {SCHEDULE_HELP}")
    src.add_argument("--host-driven", action="store_true",
                     help="no schedule: stimuli only on host commands")
    src.add_argument("--grasp", type=integer(1, MAX_LIFTS, "lifts"), metavar="LIFTS",
                     help=f"a held object lifted LIFTS times, 1..{MAX_LIFTS} (docs: Grasp): "
                          "the decoder under test grips it with GRIP commands; its scores go "
                          "to --score under \"grasp\"; the run ends after the lifts unless "
                          "--duration says otherwise")
    src.add_argument("--suite", metavar="SUITE:CASE",
                     help="play a case of a task suite (skinhil suites lists them, "
                          "docs: Suites), its trials drawn from --seed; the run ends with "
                          "the case unless --duration says otherwise")
    src.add_argument("--replay", type=Path, metavar="FILE",
                     help="play this recording (serve --record) onto the link instead of "
                          "running the board: byte for byte (serial, UDP), frame for frame "
                          "(CAN), at its recorded pace; host commands get a NACK (REPLAYING), "
                          "DECISIONs are scored against the recorded markers; the emulated "
                          "board's options (--size, --snr-db, --stopped, --duration, ...) "
                          "are refused with it")
    plays.add_argument("--speed", type=speed_value, default=1.0, metavar="X",
                       help="--replay at X times the recorded pace (default: 1; inf: as fast "
                            "as the link takes)")
    plays.add_argument("--rest", dest="rest_s", type=real(0, MAX_REST_S, "seconds"),
                       default=0.25, metavar="SECONDS",
                       help="rest after each stimulus of the random schedule, "
                            f"0..{MAX_REST_S:g} (default: 0.25)")
    plays.add_argument("--duration", dest="duration_s",
                       type=real(0, MAX_DURATION_S, "seconds", lo_open=True),
                       metavar="SECONDS",
                       help="stop after this much board time (default: run until Ctrl-C)")
    plays.add_argument("--stopped", action="store_true",
                       help="start stopped: stream only after a START command")
    board = p.add_argument_group("board")
    board.add_argument("--board-id", type=integer(0, MAX_BOARD_ID, "board id"), default=0,
                       metavar="N",
                       help=f"board id on the CAN bus, 0..{MAX_BOARD_ID} (default: 0)")
    board.add_argument("--tick", dest="tick_s",
                       type=real(0, MAX_TICK_S, "seconds", lo_open=True),
                       default=1e-3, metavar="SECONDS",
                       help="publish tick, a whole number of steps (default: 0.001)")
    board.add_argument("--fifo", dest="fifo_events",
                       type=integer(1, MAX_FIFO_EVENTS, "capacity"), default=16384,
                       metavar="EVENTS",
                       help=f"event FIFO capacity, 1..{MAX_FIFO_EVENTS} (default: 16384)")
    board.add_argument("--status-period", dest="status_period_s",
                       type=real(*STATUS_PERIOD_RANGE_S, "seconds"), default=0.1,
                       metavar="SECONDS", help="status/heartbeat period, "
                                               f"{STATUS_PERIOD_RANGE_S[0]:g}.."
                                               f"{STATUS_PERIOD_RANGE_S[1]:g} (default: 0.1)")
    board.add_argument("--reconnect", action="store_true",
                       help="when the link goes away, keep running and reopen it when it "
                            "returns")
    add_model_options(p.add_argument_group("model (skin, neurons, noise)"),
                      snr_default=DECODE_SNR_DB)  # the paper's 10 dB, as train and demo
    scoring = p.add_argument_group("scoring (the decoder under test)")
    scoring.add_argument("--response-window", dest="response_window_s",
                         type=real(0, MAX_RESPONSE_WINDOW_S, "seconds", lo_open=True),
                         default=DEFAULT_RESPONSE_WINDOW_S, metavar="SECONDS",
                         help="score the decoder under test: a DECISION answers the latest "
                              "stimulus onset before it if it arrives within this time after "
                              f"it, 0..{MAX_RESPONSE_WINDOW_S:g} (default: "
                              f"{DEFAULT_RESPONSE_WINDOW_S:g}; protocols/SPEC.md §3.5.2)")
    scoring.add_argument("--score", type=Path, metavar="FILE",
                         help="score the decoder under test on a blind link (no MARKER on "
                              "it: the truth stays on the board, see --truth) and write its "
                              "scoreboard here at the end (JSON, with every decision; its "
                              "ANSWERs per task under \"tasks\")")
    scoring.add_argument("--markers", action="store_true",
                         help="with --score: send the ground-truth MARKERs on the link all "
                              "the same (a decoder that calibrates on them, the reference "
                              "receiver scoring itself)")
    realtime = p.add_argument_group("real time")
    realtime.add_argument("--realtime", action="store_true",
                          help="run with real-time (FIFO) scheduling so other programs cannot "
                               "delay ticks (or replayed units), and spin the last 0.3 ms "
                               "before each tick instead of sleeping (needs root or "
                               "CAP_SYS_NICE)")
    realtime.add_argument("--cpu", type=cores_value, metavar="N[,N...]",
                          help="run the board on these CPU cores only (as firmware has its "
                               "core to itself): with the receiver or the decoder under test "
                               "on another core, no other program takes turns on the "
                               "board's; as many cores as --threads")
    files = p.add_argument_group("outputs (files written, what is printed; docs: Process "
                                 "output)")
    files.add_argument("--record", type=Path, metavar="FILE",
                       help="record what the board puts on the link, as it goes: CAN to a "
                            f"python-can log chosen by the extension (.blf, .asc, .log, .csv, "
                            f".trc, ...), serial and UDP to a {CAPTURE_SUFFIX} capture "
                            "(SPEC.md \"Capture files\")")
    files.add_argument("--truth", type=Path, metavar="FILE",
                       help="write the ground truth here at the end, for the operator: every "
                            "stimulus marker and every trial of the contact tasks (JSON "
                            "lines)")
    files.add_argument("--grasp-truth", type=Path, metavar="FILE",
                       help="with --grasp: append the held object's truth to FILE as the run "
                            "goes (one record a tick, skinhil.plant.HELD_DTYPE, written every "
                            "50 ms; never on the link): what demo --task grasp --view plots. "
                            "FILE is new or one this option wrote; any other file is "
                            "refused, never overwritten")
    files.add_argument("--json", action="store_true",
                     help="machine-readable output: one JSON object per line on stdout, "
                          "the ready line first and the summary line last")
    add_ready_option(files)


def _config(args: argparse.Namespace) -> BoardConfig:
    if args.schedule is not None or args.grasp is not None or args.suite is not None:
        mode = Timeline.SCHEDULE_FILE
    elif args.host_driven:
        mode = Timeline.SCHEDULE_NONE
    else:
        mode = Timeline.SCHEDULE_RANDOM
    return BoardConfig(dt_s=args.dt_s, tick_s=args.tick_s, fifo_events=args.fifo_events,
                       status_period_s=args.status_period_s, snr_db=args.snr_db,
                       noise=noise_from_args(args),
                       seed=args.seed, board_id=args.board_id, mechanics=args.mechanics,
                       readout=args.readout, amplitude=args.amplitude,
                       size=args.size, threads=args.threads, schedule_mode=mode, rest_s=args.rest_s,
                       start_running=not args.stopped, reconnect=args.reconnect,
                       response_window_s=args.response_window_s,
                       markers=args.score is None or args.markers,
                       spin_s=REALTIME_SPIN_S if args.realtime else 0.0).check()


def _claim_cpu(args: argparse.Namespace) -> None:
    """``--realtime`` and ``--cpu``: this process in the real-time class and on those cores,
    or :class:`ConfigError`."""
    if args.realtime:
        why = request_realtime()
        if why is not None:
            raise ConfigError(f"--realtime: {why}")
    if args.cpu is None:
        return
    threads = getattr(args, "threads", 1)
    if threads > len(args.cpu):
        raise ConfigError(f"--threads {threads} runs the board on {threads} cores: give "
                          f"--cpu as many ({len(args.cpu)} given)")
    why = pin_to_cores(args.cpu)
    if why is not None:
        raise ConfigError(f"--cpu: {why}")


DRAIN_NOTICE_S = 2.0
"""A stop whose drain onto the link takes longer than this (s) says so."""


def _drain_notice(board: Board) -> str | None:
    """What a clean stop waits for, when it is long (a slow link): the FIFO's drain (at
    most ``drain_timeout_s``) and the transmit queue at the link's rate."""
    link = board.link
    if link is None:
        return None
    wait_s = (board.config.drain_timeout_s if len(board.fifo) else 0.0) + link.backlog_s()
    if wait_s <= DRAIN_NOTICE_S:
        return None
    return (f"stopping: sending what is queued ({len(board.fifo)} events, "
            f"{link.queued_units()} {link.transport.unit}) takes up to "
            f"{wait_s:.0f} s on this link; Ctrl-C again stops at once")


def _undrained(board: Board) -> str:
    """What a second Ctrl-C leaves unsent."""
    link = board.link
    queued = 0 if link is None else link.queued_units()
    unit = "bytes" if link is None else link.transport.unit
    return (f"stopped at once: {len(board.fifo)} events in the FIFO and {queued} {unit} "
            "queued for the link were not sent")


def _live(board: Board) -> dict[str, Any]:
    c = board.counters
    lat = board.clock.lateness_percentiles_ms(last=LIVE_WINDOW_TICKS)
    return {"type": "status", "board_time_s": round(board.board_time_us() * 1e-6, 4),
            "generated": c.generated, "sent": c.sent, "dropped": c.dropped,
            "dropped_by": dict(c.dropped_by), "queued": len(board.fifo),
            "deadline_misses": board.clock.deadline_misses,
            "lateness_p99_ms": round(lat["p99"], 4), "lateness_max_ms": round(lat["max"], 4),
            "markers_sent": c.markers_sent, "markers_dropped": c.markers_dropped,
            "running": board.running, "link_up": board.link is not None,
            "scoreboard": board.scoreboard.summary()}


def _live_score(sb: dict[str, Any]) -> str:
    """The scoreboard's few live figures for the status line."""
    if not sb["decisions"]:
        return f"  DUT: no decision, {sb['onsets']} stimuli"
    acc = "n/a" if sb["accuracy"] is None else f"{100 * sb['accuracy']:.0f}%"
    p50 = sb["latency_ms"]["p50"]
    return (f"  DUT: {sb['decisions']} dec acc {acc} miss {sb['misses']}"
            f"{'' if p50 is None else f' p50 {p50:.0f} ms'}")


def _summary_text(s: BoardSummary) -> str:
    rate = s.sent / s.board_time_s if s.board_time_s else 0.0
    drops = ", ".join(f"{k} {v}" for k, v in s.dropped_by.items() if v) or "none"
    return (f"served {s.board_time_s:.3f} s of board time in {s.wall_s:.3f} s: "
            f"{s.generated} events generated, {s.sent} sent ({rate:.0f}/s), "
            f"{s.dropped} dropped ({drops}), {s.queued} queued; {s.ticks} ticks, "
            f"{s.deadline_misses} deadline misses, lateness p50 {s.lateness_ms['p50']:.3f} ms "
            f"p99 {s.lateness_ms['p99']:.3f} ms max {s.lateness_ms['max']:.3f} ms; "
            f"CPU {100 * s.cpu_s / max(s.wall_s, 1e-9):.1f}% of one core; "
            f"{s.commands} commands ({s.nacks} NACK), {s.link_losses} link losses; "
            f"{s.markers_sent} markers sent, {s.markers_dropped} not sent (board stopped or "
            "link down)")


def speed_value(text: str) -> float:
    """argparse type of --speed: a pace factor above 0, ``inf`` for as fast as the link
    takes."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value > 0:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: give a factor above 0 "
                                         "(1 = the recorded pace, inf = as fast as possible)")
    return value


def _replay_text(s: ReplaySummary, path: Path, unit: str) -> str:
    return (f"replayed {s.units} units of {path} ({s.recorded_s:.3f} s recorded) in "
            f"{s.wall_s:.3f} s at speed {s.speed:g}{'' if s.complete else ' (stopped early)'}"
            f": {s.wire_units} {unit} sent, "
            f"{s.events} events, {s.markers} markers; pace error p50 "
            f"{s.lateness_ms['p50']:.3f} ms p99 {s.lateness_ms['p99']:.3f} ms max "
            f"{s.lateness_ms['max']:.3f} ms; {s.commands} host commands (DECISIONs scored, "
            f"others NACK REPLAYING), {s.rx_errors} host units refused")


BOARD_OPTIONS: dict[str, str] = {
    "rest_s": "--rest", "duration_s": "--duration", "board_id": "--board-id",
    "tick_s": "--tick", "fifo_events": "--fifo", "status_period_s": "--status-period",
    "stopped": "--stopped", "reconnect": "--reconnect", "size": "--size",
    "mechanics": "--mechanics", "readout": "--readout",
    "amplitude": "--amplitude", "dt_s": "--dt", "snr_db": "--snr-db",
    "noise": "--noise", "seed": "--seed", "threads": "--threads"}
"""Options of the emulated board (dest: option), which a replay has none of."""


def _board_options_given(args: argparse.Namespace) -> list[str]:
    """The board options of ``args`` that differ from serve's defaults."""
    sub = argparse.ArgumentParser().add_subparsers()
    add_parser(sub)
    defaults = sub.choices["serve"]
    return [opt for dest, opt in BOARD_OPTIONS.items()
            if getattr(args, dest, None) != defaults.get_default(dest)]


def run_replay(args: argparse.Namespace) -> int:
    """``serve --replay FILE``: the recording checked whole, then played onto the link."""
    if args.record is not None:
        raise ConfigError("--record and --replay do not go together: a replay is already "
                          "a recording; copy the file instead")
    given = _board_options_given(args)
    if given:
        raise ConfigError(f"{', '.join(given)} set{'s' if len(given) == 1 else ''} the "
                          "emulated board; --replay plays a recording as it was (its board, "
                          "size, SNR and length are the recording's) — drop "
                          f"{'it' if len(given) == 1 else 'them'}")
    link = selected_link(args)
    check_link_fits(args.replay, link.kind)
    recording = open_recording(args.replay)
    if link.carries_frames and recording.fd != selected_can_fd(args):
        raise ConfigError(f"'{args.replay}' holds {'CAN FD' if recording.fd else 'classic CAN'}"
                          f" frames: {'add' if recording.fd else 'drop'} --fd (fd=1 in --link) "
                          "to replay them in the layout they were recorded in")
    lasts_s = recording.duration_s / args.speed
    if lasts_s > MAX_DURATION_S:
        raise ConfigError(f"replaying '{args.replay}' ({recording.duration_s:.3g} s recorded) "
                          f"at speed {args.speed:g} would take {lasts_s:.3g} s, more than "
                          f"{MAX_DURATION_S:g} s — give a larger --speed")
    if args.truth is not None:
        raise ConfigError("--truth writes a live board's truth: a replay's truth is the "
                          "recording's markers; drop --truth")
    if args.grasp_truth is not None:
        raise ConfigError("--grasp-truth writes the held object's truth of a live board "
                          "(serve --grasp): a replay holds no object; drop --grasp-truth")
    if args.markers:
        raise ConfigError("--markers puts a live board's markers on a blind link: a replay "
                          "plays the recording's units as they were recorded; drop --markers")
    score_path = check_output_path(args.score) if args.score is not None else None
    scoreboard = DecisionScoreboard(args.response_window_s)
    _claim_cpu(args)
    with open_transport(args) as transport:
        replayer = Replayer(recording, transport, args.speed, scoreboard)
        announce_ready(args, ready_record(
            "serve", describe_transport(args), True,
            () if recording.wire_version is None else (recording.wire_version,),
            replay=str(args.replay), speed=args.speed))
        if not args.quiet and not args.json:
            print(f"skinhil serve: replaying {args.replay} ({recording.units} units, "
                  f"{recording.duration_s:.3f} s) onto {describe_transport(args)} at speed "
                  f"{args.speed:g}; Ctrl-C stops", file=sys.stderr, flush=True)
        with signals.stop_event() as stop:
            summary = replayer.run(stop)
    if score_path is not None:
        write_score(score_path, score_record(scoreboard))
        say_written("serve", "the score", score_path, args.quiet)
    if args.json:
        print(json.dumps({"type": "replay", **summary.as_dict(),
                          "scoreboard": scoreboard.summary()}), flush=True)
    elif not args.quiet:
        print(_replay_text(summary, args.replay, transport.unit), flush=True)
        print(scoreboard_text(scoreboard.summary()), flush=True)
    return 0


def write_score(path: Path, score: dict[str, Any]) -> None:
    """Write ``score`` (:func:`firmware_sim.score.board_score`,
    :func:`skinhil.scoring.score_file.score_record`) to ``path`` (JSON), whole or not at all."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(score, indent=1) + "\n", encoding="utf-8")


def write_truth(path: Path, board: Board) -> None:
    """Write the board's ground truth to ``path`` (JSON lines), whole or not at all: one
    line per stimulus marker that fell due (``"type": "marker"``), one per trial of each
    contact task (``"type": "trial"``, :mod:`skinhil.scoring.tasks`)."""
    lines = [json.dumps({"type": "marker", "t_us": m.t_us, "stimulus_id": m.stimulus_id,
                         "phase": m.phase}) for m in board.truth_markers]
    if board.tasks is not None:
        lines += truth_lines(board.tasks)
    with atomic_path(path) as tmp:
        tmp.write_text("".join(line + "\n" for line in lines), encoding="utf-8")


def _snr_text(snr_db: float) -> str:
    """The banner's noise level: the SNR, and that inf means none."""
    if math.isinf(snr_db):
        return "SNR inf: NO neuron noise (deterministic)"
    return f"SNR {snr_db:g} dB neuron noise (--snr-db inf for none)"


def run(args: argparse.Namespace) -> int:
    check_ready(args)
    if args.replay is not None:
        return run_replay(args)
    if args.speed != 1.0:
        raise ConfigError("--speed sets the pace of --replay: add --replay FILE or drop it")
    if args.markers and args.score is None:
        raise ConfigError("--markers keeps the MARKERs on a scored (blind) link; without "
                          "--score the link carries them anyway: add --score FILE or drop "
                          "--markers")
    if args.record is None:
        return run_board(args, open_link=lambda: open_transport(args))
    n_channels = spring_count(args.size)
    with link_recorder(args.record, selected_link(args).kind, wire_version(n_channels),
                       int(round(args.dt_s * 1e6)), fd=selected_can_fd(args)) as recorder:
        boards: list[Board] = []

        def board_time_us() -> int:
            return boards[0].board_time_us() if boards else 0

        status = run_board(args, lambda: RecordingTransport(open_transport(args), recorder,
                                                            board_time_us), boards)
    say_written("serve", "the recording", args.record, args.quiet)
    return status


def run_board(args: argparse.Namespace, open_link: Any, made: list[Board] | None = None
              ) -> int:
    """Run the board over the links ``open_link()`` opens; ``made`` receives the board."""
    config = _config(args)
    scenario = (read_scenario(args.schedule, args.size) if args.schedule is not None
                else None)
    schedule = scenario.schedule if scenario is not None else None
    scene = scenario.scene if scenario is not None else None
    grasp = GraspParams() if args.grasp is not None else None
    duration_s = args.duration_s
    if grasp is not None:
        scene = lift_scene(grasp, args.grasp)
        if duration_s is None:  # the run ends after its lifts
            duration_s = lifts_duration_s(grasp, args.grasp)
    if args.suite is not None:
        trials = suite_trials(args.suite, args.seed, args.size)
        schedule, scene, grasp = trials.scenario.schedule, trials.scenario.scene, trials.grasp
        duration_s = trials.duration_s if duration_s is None else duration_s
        config = dataclasses.replace(config, tasks=tuple(t.name for t in trials.tasks),
                                     **announcement(*case_ref(args.suite))).check()
    tty = sys.stderr.isatty() and not args.quiet and not args.json
    where = describe_transport(args)

    def on_link(msg: str) -> None:
        if args.json:
            print(json.dumps({"type": "link", "message": msg}), flush=True)
        elif not args.quiet:
            print(("\n" if tty else "") + f"skinhil serve: {msg}", file=sys.stderr, flush=True)

    score_path = check_output_path(args.score) if args.score is not None else None
    truth_path = check_output_path(args.truth) if args.truth is not None else None
    if args.grasp_truth is not None and grasp is None:
        raise ConfigError("--grasp-truth writes a held object's truth: give --grasp LIFTS "
                          "(or --suite SUITE:grasp) too, or leave it out")
    grasp_truth_path = (check_truth_path(args.grasp_truth) if args.grasp_truth is not None
                        else None)
    # the board's model compiles as it is built (the geometric mechanics' rest forces come
    # from its kernel): say so before, with the arguments checked
    announce_cold_cache("serve")
    board = Board(config, open_link, schedule, on_link, scene, grasp)
    truth_file = (HeldTruthWriter(grasp_truth_path) if grasp_truth_path is not None
                  else None)
    if truth_file is not None:
        board.truth.object_sink = truth_file.add
    if made is not None:
        made.append(board)
    _claim_cpu(args)

    def on_second(b: Board) -> None:
        info = _live(b)
        if args.json:
            print(json.dumps(info), flush=True)
        elif tty:
            rate = info["sent"] / max(info["board_time_s"], 1e-9)
            sys.stderr.write(
                f"\r{info['board_time_s']:9.1f} s  {rate:8.0f} ev/s  sent {info['sent']}  "
                f"dropped {info['dropped']}  queued {info['queued']}  late p99 "
                f"{info['lateness_p99_ms']:.2f} ms max {info['lateness_max_ms']:.2f} ms  "
                f"misses {info['deadline_misses']}{_live_score(info['scoreboard'])}"
                f"{'' if info['link_up'] else '  LINK DOWN'}\x1b[K")
            sys.stderr.flush()

    model = board.sensor.model
    announce_ready(args, ready_record(
        "serve", where, board.link is not None, (wire_version(model.n_springs),),
        board_id=args.board_id, size=format_size(model.size), channels=model.n_springs,
        dt_s=args.dt_s, tick_s=args.tick_s, duration_s=args.duration_s))
    if not args.quiet and not args.json:
        print(f"skinhil serve: board {args.board_id} on {where}; skin {format_size(model.size)}"
              f" ({model.n_springs} channels), model on {board.config.threads} thread"
              f"{'s' if board.config.threads > 1 else ''}; mechanics "
              f"{model.params.describe_mechanics()}; {_snr_text(args.snr_db)}; Ctrl-C stops",
              file=sys.stderr, flush=True)
    try:
        def on_signal() -> str | None:
            board.end_reason = protocols.RunEndReason.SIGNAL  # what RUN_END says
            return _drain_notice(board)

        with signals.stop_event(on_signal, lambda: _undrained(board)) as stop:
            summary = board.run(duration_s, stop,
                                on_second if (args.json or tty) else None)
    finally:
        if tty:
            sys.stderr.write("\n")
        if truth_file is not None:
            truth_file.close()
            if truth_file.error is None:
                say_written("serve", "the held object's truth", truth_file.path, args.quiet)
    extra = grasp_scores(board)
    if score_path is not None:
        write_score(score_path, board_score(board))
        say_written("serve", "the score", score_path, args.quiet)
    if truth_path is not None:
        write_truth(truth_path, board)
        say_written("serve", "the ground truth", truth_path, args.quiet)
    if args.json:
        print(line({"type": SUMMARY, **summary.as_dict(), **extra}), flush=True)
    elif not args.quiet:
        print(_summary_text(summary), flush=True)
        print(scoreboard_text(summary.scoreboard), flush=True)
        if extra:
            print(grasp_text(extra["grasp"]), flush=True)
    if board.touch is not None and not args.quiet:
        truth = board.truth.records()
        text = (f"contact truth kept on the board (never sent): {board.truth.ticks} ticks of "
                f"{len(board.touch.scene.contacts)} contact(s), peak normal force "
                f"{truth['normal_n'].max(initial=0.0):.3g} N")
        print(json.dumps({"type": "truth", "ticks": board.truth.ticks,
                          "peak_normal_n": float(truth["normal_n"].max(initial=0.0))})
              if args.json else text, flush=True)
    if truth_file is not None and truth_file.error is not None:  # the run's rest is kept
        raise ConfigError(f"the held object's truth file '{truth_file.path}' stopped after "
                          f"{truth_file.records} records of this run: "
                          f"{truth_file.error.strerror or truth_file.error} — free some space "
                          "or choose another folder")
    return 0
