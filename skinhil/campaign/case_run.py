"""One case played: the board (``skinhil serve``) on the link, the decoder on the other end,
the board's score file judged by the case's criteria and its health by the rig's bounds.

On the bench's own link (:class:`~skinhil.campaign.relay.RelayLink`) the decoder is the
reference receiver, ``skinhil listen --answer --json``, started first: the board starts once
its ready line says it listens, so its first stimulus does not wait in a queue. The board's
health is read from the summary line of ``serve --json`` (:mod:`skinhil.process_output`).
On a link the user gives (``--port``, ``--udp``, ``--can``) the decoder under test is the
user's, already running there.

A case's outcome is ``passed``, ``failed`` (a criterion does not hold: the decoder's
failure) or ``error`` (the rig's: a fault past its bound, the board or decoder process
ending badly, a timeout, a score file without a criterion's key); an error wins over a
failure, and the criteria are kept beside it.
"""

from __future__ import annotations

import datetime
import json
import logging
import re
import subprocess
import sys
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from skinhil import child_processes
from skinhil.campaign.campaign_file import PARAMETERS, Case
from skinhil.campaign.criteria import Criterion, MissingKey, answers
from skinhil.campaign.relay import RelayLink
from skinhil.campaign.rig import RigBounds, board_health, rig_faults
from skinhil.process_output import READY, SUMMARY, last_record, records
from skinhil.transports.base import DEFAULT_BAUD
from skinhil.transports.faults import FaultParams

log = logging.getLogger(__name__)

POLL_S = 0.1
"""How often (s) the case's processes are looked at."""
DECODER_READY_S = 120.0
"""Longest wait (s) for the reference receiver to listen (a cold kernel cache compiles)."""
TRUTH_NAME = "truth.jsonl"
"""A suite case's truth file (``serve --truth``) in the case's folder."""
DECODER_END_S = 10.0
"""How long (s) the reference receiver may take to end after the board's RUN_END."""


@dataclass(frozen=True)
class BenchLink:
    """Where the cases play: ``link_args`` (serve's link options, e.g. ``--port P``) with
    the user's decoder there, or, with ``model``, the bench's own pty link and the reference
    receiver decoding with that model (``baud``, ``faults``: the link's).

    On the bench's own link, ``answer_with`` says who answers the tasks (``listen
    --answer-with``: ``reference``, ``random`` or ``oracle``; the oracle answers a case from
    the truth file ``oracle_truths[case id]``), and ``grip_readout`` (a load readout file)
    adds the reference grip controller (``listen --grip-readout``) in the cases that hold
    an object."""

    link_args: tuple[str, ...] = ()
    model: Path | None = None
    baud: int = DEFAULT_BAUD
    faults: FaultParams | None = None
    answer_with: str = "reference"
    oracle_truths: Mapping[str, Path] = field(default_factory=dict)
    grip_readout: Path | None = None

    def decoder_args(self, case: Case) -> list[str]:
        """``listen``'s answering options for ``case`` on the bench's own link."""
        out = ["--answer"]
        if self.answer_with != "reference":
            out += ["--answer-with", self.answer_with]
        if self.answer_with == "oracle":
            out += ["--oracle-truth", str(self.oracle_truths.get(case.id, "no-truth-recorded"))]
        if self.grip_readout is not None and case.holds_object:
            out += ["--grip-readout", str(self.grip_readout)]
        return out


class Stopped(Exception):
    """The campaign was asked to stop during a case (the case is not recorded)."""


def _python_skinhil(*args: str) -> list[str]:
    return [sys.executable, "-m", "skinhil", *args]


def serve_args(case: Case, score: Path) -> list[str]:
    """``skinhil serve``'s options for ``case`` (beside the link's). A suite case's board
    plays ``--suite SUITE:CASE``, ends by itself and writes its truth beside the score
    (:data:`TRUTH_NAME`: what an oracle answers from)."""
    out = ["--seed", str(case.seed), "--score", str(score), "--json", "--reconnect"]
    if case.scenario.suite is None or "duration_s" in case.parameters:
        out = ["--duration", f"{case.duration_s!r}", *out]
    if case.scenario.suite is not None:
        out += ["--suite", case.scenario.suite, "--truth", str(score.parent / TRUTH_NAME)]
    for name, value in sorted(case.parameters.items()):
        if name not in ("duration_s", "seed"):
            out += [PARAMETERS[name][0], str(value)]
    if case.scenario.file is not None:
        out += ["--schedule", str(case.scenario.file)]
    return out


def slug(text: str) -> str:
    """``text`` as a file name."""
    return re.sub(r"[^A-Za-z0-9_.=,+-]+", "_", text)[:120]


def _last_line(path: Path) -> str:
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").strip().splitlines()
    except OSError:
        return ""
    return lines[-1] if lines else ""


def _record(path: Path, kind: str) -> dict[str, Any] | None:
    """The last line of type ``kind`` (:data:`~skinhil.process_output.READY`,
    :data:`~skinhil.process_output.SUMMARY`) of the ``--json`` output in ``path``, or
    None."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    return last_record(records(text), kind)


class _Process:
    """A child process with its output in files of the case's folder."""

    def __init__(self, cmd: list[str], folder: Path, stem: str) -> None:
        self.out_path, self.err_path = folder / f"{stem}.out", folder / f"{stem}.err"
        self._files: list[IO[bytes]] = [open(self.out_path, "wb"), open(self.err_path, "wb")]
        self.popen = child_processes.start(cmd, stdin=subprocess.DEVNULL,
                                           stdout=self._files[0], stderr=self._files[1])
        self.ended_by_us = False

    def end(self, grace_s: float = 5.0) -> None:
        """Stop it (SIGTERM, then SIGKILL after ``grace_s``) if it still runs."""
        if self.popen.poll() is None:
            self.ended_by_us = True
            self.popen.terminate()
            try:
                self.popen.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()
        for f in self._files:
            f.close()


def _wait_ready(decoder: _Process, stop: threading.Event, deadline: float) -> str | None:
    """Wait until the reference receiver listens; None, or what went wrong."""
    while time.monotonic() < deadline:
        if stop.is_set():
            raise Stopped
        if _record(decoder.out_path, READY) is not None:
            return None
        if decoder.popen.poll() is not None:
            return (f"the decoder process ended with status {decoder.popen.returncode} "
                    f"before the board started: {_last_line(decoder.err_path)}")
        time.sleep(POLL_S)
    return f"the decoder did not listen within {DECODER_READY_S:g} s"


def _play(case: Case, folder: Path, link: BenchLink, relay: RelayLink | None, rig: RigBounds,
          stop: threading.Event) -> list[str]:
    """Run the board (and the reference receiver) for ``case``; the processes' faults."""
    score = folder / "score.json"
    decoder: _Process | None = None
    board: _Process | None = None
    faults: list[str] = []
    try:
        if relay is not None:
            assert link.model is not None
            size = case.parameters.get("size")
            decoder = _Process(_python_skinhil(
                "listen", "--port", relay.decoder_path, "--baud", str(link.baud), "--model",
                str(link.model), *link.decoder_args(case), "--json",
                *(["--size", str(size)] if size else [])),
                folder, "decoder")
            t0 = time.monotonic()
            why = _wait_ready(decoder, stop, t0 + DECODER_READY_S)
            if why is not None:
                return [why]
            log.info("%s: the reference receiver listens after %.1f s", case.id,
                     time.monotonic() - t0)
            link_args = ["--port", relay.board_path, "--baud", str(link.baud)]
        else:
            link_args = list(link.link_args)
        board = _Process(_python_skinhil("serve", *link_args, *serve_args(case, score)),
                         folder, "board")
        t_board = time.monotonic()
        deadline = t_board + case.duration_s + rig.timeout_s
        while board.popen.poll() is None:
            if stop.is_set():
                raise Stopped
            if time.monotonic() > deadline:
                return [f"timed out: the board ran {case.duration_s + rig.timeout_s:g} s of "
                        f"wall time for {case.duration_s:g} s of board time"]
            time.sleep(POLL_S)
        log.info("%s: the board process ran %.1f s", case.id, time.monotonic() - t_board)
        if board.popen.returncode != 0:
            faults.append(f"the board process ended with status {board.popen.returncode}: "
                          f"{_last_line(board.err_path) or 'no message'}")
        if decoder is not None:  # it ends at the board's RUN_END
            try:
                decoder.popen.wait(timeout=DECODER_END_S)
            except subprocess.TimeoutExpired:
                pass
            if decoder.popen.poll() not in (None, 0):  # during the run or after it
                faults.append(f"the decoder process crashed (status "
                              f"{decoder.popen.returncode}): {_last_line(decoder.err_path)}")
        return faults
    finally:
        for p in (board, decoder):
            if p is not None:
                p.end()


def run_case(case: Case, folder: Path, link: BenchLink, rig: RigBounds,
             stop: threading.Event) -> dict[str, Any]:
    """Play ``case`` with its files in ``folder``; its record (the summary's ``cases``
    entry). Raises :class:`Stopped` when ``stop`` is set meanwhile."""
    folder.mkdir(parents=True, exist_ok=True)
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    t0 = time.monotonic()
    relay = RelayLink(link.baud, link.faults) if link.model is not None else None
    try:
        if relay is not None:
            relay.start()
        errors = _play(case, folder, link, relay, rig, stop)
        if stop.is_set():  # a Ctrl-C from a terminal also stops the children: not a fault
            raise Stopped
    finally:
        if relay is not None:
            relay.stop()
    summary = _record(folder / "board.out", SUMMARY)
    health = board_health(summary) if summary is not None else None
    tap = relay.counters() if relay is not None else None
    if summary is None and not errors:
        errors.append(f"the board wrote no summary: {_last_line(folder / 'board.err')}")
    errors += rig_faults(rig, health, tap)
    if relay is not None and relay.error is not None:
        errors.append(f"the bench's link failed: {relay.error}")
    verdicts: list[dict[str, Any]] = []
    failed: list[str] = []
    score = _read_score(folder / "score.json")
    if score is None and not errors:
        errors.append("the board wrote no score file")
    for criterion in case.criteria if score is not None else ():
        try:
            value = criterion.value(score or {})
        except MissingKey as exc:
            errors.append(f"{criterion}: {exc}")
            verdicts.append({"criterion": str(criterion), "value": None, "holds": None})
            continue
        holds = criterion.holds(value)
        verdicts.append({"criterion": str(criterion), "value": value, "holds": holds})
        if not holds:
            failed.append(f"{criterion} (was {'null' if value is None else f'{value:g}'})")
    failed = silence(health, score, case.criteria) + failed
    outcome = "error" if errors else "failed" if failed else "passed"
    message = "; ".join(errors) if errors else "; ".join(failed)
    return {"id": case.id, "scenario": case.scenario.name, "parameters": case.parameters,
            "repetition": case.repetition + 1, "seed": case.seed, "outcome": outcome,
            "message": message, "criteria": verdicts,
            "errors": errors, "rig": {"board": health, "link": tap},
            "started": started, "wall_s": round(time.monotonic() - t0, 3),
            "folder": str(folder)}


SENT_NOTHING = "the decoder sent nothing"
"""Why a case fails whose board received no host command (whatever its criteria)."""
NO_ANSWER = "the decoder answered nothing, and criteria of upper bounds alone need an answer"
"""Why a case fails whose criteria are all upper bounds when the score holds no answer."""


def silence(health: Mapping[str, Any] | None, score: Mapping[str, Any] | None,
            criteria: tuple[Criterion, ...]) -> list[str]:
    """The failures of a silent decoder: :data:`SENT_NOTHING` when the board's summary
    counts no host command; :data:`NO_ANSWER` when every criterion is an upper bound
    (``false_alarms <= 2`` holds with no decoder at all) and the score file counts no
    answer (:func:`~skinhil.campaign.criteria.answers`)."""
    if health is not None and health["commands"] == 0:
        return [SENT_NOTHING]
    if score is not None and criteria and all(c.upper_bound for c in criteria) \
            and answers(score) == 0:
        return [NO_ANSWER]
    return []


def _read_score(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None

