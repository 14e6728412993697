"""``skinhil listen``: the reference receiver and online classifier on a serial port, CAN or
UDP; several boards at once on one CAN bus (``--board-id 0,5,9``) or one UDP port."""

from __future__ import annotations

import argparse
import datetime
import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from protocols.constants import KNOWN_VERSIONS
from skinhil.cli import signals
from skinhil.cli.conventions import MODEL_HELP
from skinhil.cli.direction_names import class_names
from skinhil.cli.kernel_notice import announce_cold_cache
from skinhil.cli.lab_outputs import (
    LabOutputs,
    add_lab_output_args,
    check_lab_outputs,
    lab_outputs,
    provenance,
)
from skinhil.cli.nwb_options import add_nwb_args, nwb_metadata
from skinhil.cli.options import add_size_option
from skinhil.cli.ready_option import add_ready_option, announce_ready, check_ready
from skinhil.cli.transport_args import (
    add_transport_args,
    describe_transport,
    open_transport,
    selected_link,
    serial_baud,
)
from skinhil.cli.values import MAX_DURATION_S, integer, real, udp_allow_value
from skinhil.cli.written import say_written
from skinhil.errors import ConfigError
from skinhil.model.geometry import build_mesh, format_size, spring_count
from skinhil.model.skin import SkinParams
from skinhil.nwb import require_pynwb, write_session
from skinhil.output_files import check_output_path
from skinhil.process_output import SUMMARY, ready_record
from skinhil.receiver import (
    BusReceiver,
    DecisionAnswerer,
    Receiver,
    ReceiverListener,
    ScoredDecision,
)
from skinhil.receiver.announcement import Announcement
from skinhil.receiver.bus import MAX_UDP_SOURCES, BoardKey
from skinhil.receiver.grip_reflex import GripController, LoadReadout, SlipReflex
from skinhil.receiver.model_file import load_window_decoder
from skinhil.receiver.task_answer import ANSWERERS, TaskAnswerer
from skinhil.recording import SessionRecorder

STATUS_PERIOD_S = 1.0
"""Seconds between link-counter lines."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "listen", help="receive a board's stream and classify force direction online",
        description="Decode a board's AER stream, PSP-filter it on board time, detect each "
                    "stimulus onset from the activity and classify its direction with a "
                    "trained model (skinhil train). Markers in the stream, when present, "
                    "score the decisions: running accuracy, confusion matrix, latency.")
    add_transport_args(p, udp_listen=True)
    p.add_argument("--model", type=Path, metavar="NPZ", help=MODEL_HELP)
    p.add_argument("--board-id", dest="board_ids", type=_board_ids, default=[0],
                   metavar="N[,N...]",
                   help="board id(s) on the CAN bus, e.g. 0,5,9 to decode three boards at "
                        "once (default: 0); on UDP every board that sends is decoded")
    p.add_argument("--duration", dest="duration_s",
                   type=real(0, MAX_DURATION_S, "seconds", lo_open=True), metavar="SECONDS",
                   help="stop after this many seconds (default: until Ctrl-C)")
    p.add_argument("--json", action="store_true",
                   help="one JSON object per line: the ready line first, decisions, link "
                        "counters, the summary line last (docs: Process output)")
    add_ready_option(p)
    p.add_argument("--record", type=Path, metavar="FILE",
                   help="save events (tonic-compatible), markers and decisions to this .npz, "
                        "or to NWB if it ends in .nwb (pip install \"skinhil[nwb]\")")
    p.add_argument("--answer", action="store_true",
                   help="send each decision back to the board as a DECISION and, at each "
                        "onset, ANSWERs of the contact tasks (where, how hard, slip, "
                        "vibration), so the board scores this receiver as a decoder under "
                        "test (serve --score; protocols/SPEC.md §3.5.3)")
    p.add_argument("--answer-with", choices=ANSWERERS, default="reference",
                   help="with --answer: who answers the contact tasks: the reference "
                        "decoders (default), random values at the same onsets, or the "
                        "oracle (the truth of --oracle-truth, through the same link)")
    p.add_argument("--oracle-truth", type=Path, metavar="FILE",
                   help="with --answer-with oracle: the truth of an earlier run of the same "
                        "scenario (serve --truth FILE)")
    p.add_argument("--grip-readout", type=Path, metavar="NPZ",
                   help="with --answer: grip a held object with the reference grip "
                        "controller (skinhil.receiver.grip_reflex), reading the load with "
                        "this readout (skinhil demo --task grasp fits and caches one)")
    p.add_argument("--udp-max-sources", type=integer(1, 4096, "count"),
                   default=None, metavar="N",
                   help=f"with --udp: decode at most N sending boards; datagrams of further "
                        f"sources are refused and counted (default: {MAX_UDP_SOURCES})")
    p.add_argument("--udp-allow", type=udp_allow_value,
                   metavar="HOST[:PORT][,...]",
                   help="with --udp: decode only these senders (an IP address, or "
                        "address:port; host names are not resolved); "
                        "datagrams of others are refused and counted")
    add_size_option(p)
    add_lab_output_args(p, truth=True)
    add_nwb_args(p)


def _board_ids(text: str) -> list[int]:
    try:
        ids = [int(v, 0) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give board ids such as 0 or 0,5,9") \
            from None
    if not ids or any(not 0 <= b <= 15 for b in ids) or len(set(ids)) != len(ids):
        raise argparse.ArgumentTypeError(f"{text!r}: board ids are distinct, 0..15")
    return ids


class LivePrinter(ReceiverListener):
    """Prints each decision (text or JSON lines) and link problems as they happen; with
    ``board`` (several boards on the link) each line says which board."""

    def __init__(self, receiver: Receiver, as_json: bool, names: dict[int, str],
                 board: BoardKey | None = None) -> None:
        self.receiver = receiver
        self.as_json = as_json
        self.names = names
        self.board = board

    def _name(self, label: int | None) -> str:
        """The stimulus's name: the board's table (its SESSION) first, else the built-ins."""
        if label is None:
            return "-"
        return self.receiver.stimuli.get(label) or self.names.get(label, str(label))

    def on_decision(self, decision: ScoredDecision) -> None:
        p = decision.prediction
        sb = self.receiver.scoreboard
        if self.as_json:
            print(json.dumps({
                "type": "decision", **({} if self.board is None else {"board": self.board}),
                "t_s": p.detect_t_us * 1e-6, "label": p.label,
                "name": self._name(p.label), "true_label": decision.true_label,
                "correct": decision.correct, "latency_board_ms": _ms(decision.latency_board_s),
                "latency_host_ms": _ms(decision.latency_host_s),
                "running_accuracy": None if sb.scored == 0 else sb.accuracy}), flush=True)
            return
        mark = {True: "ok", False: "WRONG", None: "(no marker)"}[decision.correct]
        lat = "" if decision.latency_host_s is None else \
            f"  latency {1e3 * decision.latency_host_s:5.1f} ms"
        truth = "" if decision.true_label is None else f"  true {self._name(decision.true_label)}"
        acc = "" if sb.scored == 0 else f"  running {100 * sb.accuracy:5.1f}% ({sb.scored})"
        where = "" if self.board is None else f"board {self.board}  "
        print(f"{where}{p.detect_t_us * 1e-6:9.3f} s  {self._name(p.label):>13}{truth:>19}  "
              f"{mark:<5}{lat}{acc}", flush=True)

    def on_announcement(self, announcement: Announcement) -> None:
        info = announcement.as_dict()
        if self.as_json:
            print(json.dumps({"type": "session", **({} if self.board is None else {
                "board": self.board}), **info}), flush=True)
            return
        where = "" if self.board is None else f"board {self.board}: "
        print(f"skinhil listen: {where}{announced_text(info)}", file=sys.stderr, flush=True)

    def on_link_error(self, message: str) -> None:
        if self.as_json:
            print(json.dumps({"type": "link_error", "message": message}), flush=True)
        else:
            print(f"skinhil listen: link error: {message}", file=sys.stderr, flush=True)


def announced_text(info: dict[str, Any]) -> str:
    """One line of what the board announced (:meth:`Announcement.as_dict`)."""
    suite = info["suite"]
    parts = [f"suite {suite['id']}:{suite['case']}" if suite else "no suite"]
    for name, t in info["tasks"].items():
        tol = "" if t["tolerance"] is None else f" within {t['tolerance']:g} {t['unit']}"
        classes = ("" if not t["classes"] else
                   " of " + ", ".join(f"{c:g}" for c in t["classes"])
                   + (f" {t['unit']}" if t["tolerance"] is None and t["unit"] else ""))
        parts.append(f"{name}{tol}{classes}")
    if info["held_object"]:
        parts.append("an object held (GRIP)")
    return "; ".join(parts)


def _ms(value: float | None) -> float | None:
    return None if value is None or math.isnan(value) else round(1e3 * value, 3)


def summary(receiver: Receiver, wall_s: float) -> dict[str, Any]:
    """Final figures of a session: accuracy, confusion, latencies, link and loss counters."""
    sb = receiver.scoreboard
    lat_b, lat_h = sb.latencies_s(), sb.latencies_s(host=True)

    def pct(a: np.ndarray, q: float) -> float | None:
        return None if a.size == 0 else round(1e3 * float(np.percentile(a, q)), 3)

    return {"type": SUMMARY, "wall_s": round(wall_s, 3),
            "board_time_s": receiver.classifier.board_time_us * 1e-6,
            "stimuli_scored": sb.scored, "correct": sb.correct, "misses": sb.misses,
            "false_alarms": sb.false_alarms,
            "accuracy": None if sb.scored == 0 else sb.accuracy,
            "classes": list(sb.classes), "confusion": sb.confusion.tolist(),
            "decision_latency_board_ms": {"p50": pct(lat_b, 50), "p99": pct(lat_b, 99)},
            "decision_latency_host_ms": {"p50": pct(lat_h, 50), "p99": pct(lat_h, 99)},
            "link": receiver.link_report().as_dict(),
            "socket_buffer": socket_buffer(receiver.transport),
            "session": receiver.announcement.as_dict(),
            "run_end": None if receiver.run_end is None else {
                "t_s": receiver.run_end.t_us * 1e-6,
                "reason": getattr(receiver.run_end.reason, "name", receiver.run_end.reason)}}


def print_summary(info: dict[str, Any], names: dict[int, str]) -> None:
    """The summary as text."""
    if info["accuracy"] is None:
        print("no ground-truth markers scored (the stream had none, or no stimulus yet)")
    else:
        print(f"accuracy {100 * info['accuracy']:.1f}% ({info['correct']}/"
              f"{info['stimuli_scored']} stimuli; {info['misses']} onsets missed, "
              f"{info['false_alarms']} false alarms)")
        classes = info["classes"]
        width = max(6, *(len(names.get(c, str(c))) for c in classes))
        print("confusion (rows: true, columns: predicted):")
        print(" " * width + " " + " ".join(f"{c:>4}" for c in classes))
        for c, row in zip(classes, info["confusion"], strict=True):
            print(f"{names.get(c, str(c)):>{width}} " + " ".join(f"{v:>4}" for v in row))
    for key, label in (("decision_latency_board_ms", "decision latency from onset, board time"),
                       ("decision_latency_host_ms", "decision latency from onset, host")):
        d = info[key]
        if d["p50"] is not None:
            print(f"{label}: p50 {d['p50']:.1f} ms, p99 {d['p99']:.1f} ms")
    print_link(info["link"])
    print_socket_buffer(info.get("socket_buffer"))
    end = info.get("run_end")
    if end is not None:
        print(f"the board's run ended at {end['t_s']:.3f} s board time ({end['reason']})")


def print_link(link: dict[str, Any]) -> None:
    """One line of link and loss counters."""
    print(f"link: {link['events_decoded']} events decoded, {link['frames_ok']} frames ok, "
          f"{link['crc_errors']} CRC errors, {link['seq_gaps']} sequence gaps "
          f"({link['frames_lost']} frames lost), {link['duplicates']} duplicates, "
          f"{link['late_events']} late events, {link.get('acks_lost', 0)} ACKs lost; board: "
          f"{link['board_generated']} generated, "
          f"{link['board_sent']} sent, {link['board_dropped']} dropped; "
          f"{link['lost_on_link']} lost on the link"
          + _joined_text(link.get("sent_before_join", 0)))


def _joined_text(sent_before: int) -> str:
    """The late-join note of the link line: what the board had sent before the receiver's
    first STATUS and it never saw."""
    if not sent_before:
        return ""
    return (f" (joined late: the board had sent {sent_before} events before the first "
            "status received; those are not counted lost)")


def bus_summary(bus: BusReceiver, wall_s: float) -> dict[str, Any]:
    """Final figures of every board on the link and the combined link counters."""
    return {"type": SUMMARY, "wall_s": round(wall_s, 3),
            "boards": {str(k): summary(rx, wall_s) for k, rx in bus.boards.items()},
            "foreign_frames": bus.foreign_frames, "refused_datagrams": bus.refused_datagrams,
            "link": bus.combined_report().as_dict(),
            "socket_buffer": socket_buffer(bus.transport)}


def socket_buffer(transport: Any) -> dict[str, int] | None:
    """The receive buffer (bytes) the link's socket asked of the kernel and was granted
    (``granted < asked``: the kernel capped it at ``net.core.rmem_max``), or None where the
    link has no socket buffer of its own (serial, pty)."""
    asked = int(getattr(transport, "rcvbuf_asked", 0) or 0)
    if not asked:
        return None
    return {"asked": asked, "granted": int(getattr(transport, "rcvbuf_granted", 0) or 0)}


def print_socket_buffer(buf: dict[str, int] | None) -> None:
    """The socket buffer line, when the kernel granted less than asked."""
    if buf is not None and buf["granted"] < buf["asked"]:
        print(f"socket receive buffer {buf['granted']} bytes granted of {buf['asked']} asked "
              "(the kernel's net.core.rmem_max): data is lost if listen stalls longer than "
              "that holds")


def listen_until_stopped(args: argparse.Namespace, rx: Receiver | BusReceiver,
                         link_line: Callable[[], dict[str, Any]],
                         gone: Callable[[], bool]) -> None:
    """Poll ``rx`` until Ctrl-C/SIGTERM, ``--duration`` (s) or ``gone()``; with ``--json``
    print ``link_line()`` every STATUS_PERIOD_S; then decode what the link already received
    (:meth:`Receiver.drain`), flush ``rx`` and shut its transport."""
    t0 = time.monotonic()
    next_line = t0 + STATUS_PERIOD_S
    try:
        with signals.stop_event(on_second=lambda: "stopped at once: what the link had "
                                                  "received but not yet decoded was dropped") \
                as stop:
            while not stop.is_set() and not gone():
                now = time.monotonic()
                if args.duration_s is not None and now - t0 >= args.duration_s:
                    break
                rx.poll(0.02)
                if args.json and now >= next_line:
                    next_line += STATUS_PERIOD_S
                    print(json.dumps({"type": "link", **link_line()}), flush=True)
            rx.drain()  # what the link already received is decoded before the totals
            rx.flush()
    finally:
        rx.transport.shutdown()


def say_ready(args: argparse.Namespace, boards: list[int] | None) -> None:
    """The ready line (:func:`announce_ready`) and, without ``--json``, the banner on
    stderr: the link is open and decoding starts; ``boards``: the board ids decoded (None:
    every board that sends)."""
    announce_ready(args, ready_record(
        "listen", describe_transport(args), True, KNOWN_VERSIONS, boards=boards,
        model=str(args.model), size=format_size(args.size),
        answer=args.answer_with if args.answer else None))
    if not args.json:
        which = (", boards as they send" if boards is None else "" if len(boards) == 1
                 else f", boards {', '.join(map(str, boards))}")
        print(f"skinhil listen: {describe_transport(args)}{which}, model {args.model}; "
              "Ctrl-C stops", file=sys.stderr, flush=True)


def run_bus(args: argparse.Namespace, bus: BusReceiver, names: dict[int, str]) -> int:
    """``listen`` over several boards: per-board decisions and summaries, a combined view."""
    say_ready(args, list(args.board_ids) if bus.transport.carries_frames else None)
    t0 = time.monotonic()
    listen_until_stopped(args, bus, lambda: {
        "boards": {str(k): r.as_dict() for k, r in bus.link_reports().items()},
        "combined": bus.combined_report().as_dict()}, lambda: bus.link_down)
    info = bus_summary(bus, time.monotonic() - t0)
    if args.json:
        print(json.dumps(info), flush=True)
        return 0
    for key, board in info["boards"].items():
        print(f"board {key}:")
        print_summary(board, names)
    print(f"all {len(info['boards'])} boards ({info['foreign_frames']} frames of other boards):")
    print_link(info["link"])
    print_socket_buffer(info["socket_buffer"])
    return 0


def run(args: argparse.Namespace) -> int:
    check_ready(args)
    link = selected_link(args)
    if not link.whole_datagrams and (args.udp_allow is not None
                                     or args.udp_max_sources is not None):
        raise ConfigError("--udp-allow and --udp-max-sources choose the senders of a UDP "
                          "link: use them with --udp")
    if args.udp_max_sources is None:
        args.udp_max_sources = MAX_UDP_SOURCES
    several = len(args.board_ids) > 1 or link.whole_datagrams
    if several and not (link.carries_frames or link.whole_datagrams):
        raise ConfigError(f"a {link.kind} link carries one board: give one --board-id")
    if several and args.record is not None:
        raise ConfigError("--record saves one board's session: use it with one board on "
                          "--port or --can")
    if several and args.answer:
        raise ConfigError("--answer sends one board its decisions: use it with one board on "
                          "--port or --can")
    if not args.answer and (args.answer_with != "reference" or args.oracle_truth is not None):
        raise ConfigError("--answer-with and --oracle-truth choose who answers: add --answer")
    if args.grip_readout is not None and not args.answer:
        raise ConfigError("--grip-readout grips the board's held object: add --answer")
    if (args.answer_with == "oracle") != (args.oracle_truth is not None):
        raise ConfigError("the oracle answers from a truth file: give --answer-with oracle "
                          "with --oracle-truth FILE (serve --truth FILE), or neither")
    record = None if args.record is None else check_output_path(args.record, (".npz", ".nwb"))
    args.nwb_meta = nwb_metadata(args, record is not None and record.suffix.lower() == ".nwb")
    if record is not None and record.suffix.lower() == ".nwb":
        require_pynwb()
    check_lab_outputs(args, args.size)
    if args.model is None:
        from skinhil.cli.demo_cache import demo_decoder

        args.model = demo_decoder(args.size, args.quiet, serial_baud(args))
    decoder = load_window_decoder(args.model, n_channels=spring_count(args.size))
    transport = open_transport(args)
    announce_cold_cache("listen")
    names = class_names()
    if several:
        lab = LabOutputs(args, names, args.size, "listen",
                         provenance(describe_transport(args), args.model))
        try:
            bus = BusReceiver(transport, decoder,
                              args.board_ids if transport.carries_frames else (),
                              max_sources=args.udp_max_sources, allow=args.udp_allow,
                              listeners=lambda key, rx: [LivePrinter(rx, args.json, names, key),
                                                         *lab.attach(key, rx)])
            return run_bus(args, bus, names)
        finally:
            lab.close()
    receiver = Receiver(transport, decoder, board_id=args.board_ids[0],
                        reopen=lambda: open_transport(args))
    receiver.add_listener(LivePrinter(receiver, args.json, names))
    answerer = (DecisionAnswerer(receiver) if args.answer and args.answer_with == "reference"
                else None)
    tasks = (TaskAnswerer(receiver, args.answer_with, args.oracle_truth,
                          encoder=answerer.encoder if answerer is not None else None)
             if args.answer else None)
    grips = None
    if args.grip_readout is not None:
        grips = GripController(transport, SlipReflex(LoadReadout.load(
            args.grip_readout, spring_count(args.size))), args.board_ids[0])
        grips.encoder = answerer.encoder if answerer is not None else grips.encoder
    for listener in (answerer, tasks, grips):
        if listener is not None:
            receiver.add_listener(listener)
    if record is None:
        info = listen_one(args, receiver, names, answerer, tasks)
    else:
        with SessionRecorder(record.parent) as recorder:
            receiver.add_listener(recorder)
            info = listen_one(args, receiver, names, answerer, tasks)
            save_session(args, recorder, names, info, receiver)
        say_written("listen", "the session", args.record)
    if args.json:
        print(json.dumps(info), flush=True)
    else:
        print_summary(info, names)
        if answerer is not None:
            a = info["answers"]
            print(f"answers: {a['sent']} DECISIONs sent to the board ({a['acked']} ACK, "
                  f"{a['nacked']} NACK, {a['unsent']} not sent)")
        if tasks is not None:
            t = info["task_answers"]
            print(f"task answers ({t['answerer']}): sent {t['sent']}, ACK {t['acked']}, "
                  f"NACK {t['nacked']}, {t['unsent']} not sent")
    return 0


def listen_one(args: argparse.Namespace, receiver: Receiver, names: dict[int, str],
               answerer: DecisionAnswerer | None = None,
               tasks: TaskAnswerer | None = None) -> dict[str, Any]:
    """Receive until Ctrl-C or --duration; the summary (with ``answerer``'s DECISION counts
    when the receiver answers the board)."""
    t0 = time.monotonic()
    with lab_outputs(args, receiver, names, args.size, "listen",
                     answerer.as_dict if answerer is not None else None,
                     provenance(describe_transport(args), args.model)):
        say_ready(args, [args.board_ids[0]])
        listen_until_stopped(args, receiver, lambda: receiver.link_report().as_dict(),
                             lambda: receiver.run_end is not None)  # the board finished
    info = summary(receiver, time.monotonic() - t0)
    if answerer is not None:
        info["answers"] = answerer.as_dict()
    if tasks is not None:
        info["task_answers"] = tasks.as_dict()
    return info


def save_session(args: argparse.Namespace, recorder: SessionRecorder, names: dict[int, str],
                 info: dict[str, Any], receiver: Receiver) -> None:
    """Write the recorded session to --record: NWB for .nwb (its start time the board's
    start on the wall clock, by the receiver's clock model), else .npz."""
    if args.record.suffix.lower() == ".nwb":
        wall = receiver.clock.wall_time_s(0)
        start = None if wall is None else datetime.datetime.fromtimestamp(wall, datetime.UTC)
        p = SkinParams(size=args.size)
        write_session(args.record, mesh=build_mesh(p.spacing_m, p.layer_gap_m, p.size),
                      events=recorder.events, markers=recorder.markers,
                      decisions=recorder.decisions, names=names,
                      description=f"skinhil listen: {describe_transport(args)}, "
                                  f"model {args.model}", start=start, meta=args.nwb_meta)
    else:
        recorder.save(args.record, {"model": str(args.model), "link": describe_transport(args),
                                    "summary": info})

