"""The emulated sensor board: skin, neurons and link running together in real time.

Per publish tick ``k`` (default 1 ms = 10 steps of 0.1 ms), due at ``t0 + (k+1)·tick``
(:class:`firmware_sim.clock.TickClock`), in this order:

1. stimulus: the external forces of the timeline at each step's start time
   (:class:`skinhil.model.timeline.Timeline`), a block (steps, 77, 3) N;
2. model: ``SkinStepper.advance`` then ``NeuronPopulation.step_block``
   (:class:`skinhil.model.sensor.SkinSensor`): spikes (steps, 338). With ``threads`` > 1 the
   neurons run two ticks behind the mechanics, on threads of their own
   (:class:`skinhil.model.pipeline.SensorPipeline`): the tick publishes the spikes of two ticks
   before, two ticks more latency for a tick that costs the larger stage, not the sum;
3. events: spikes → events stamped with board time in µs (step resolution) → counted as
   generated → the event FIFO (or dropped by reason, :mod:`firmware_sim.counters`);
4. host commands received since the last tick are executed and answered (ACK/NACK); a
   DECISION of the decoder under test is stamped with the board time and scored
   (:attr:`Board.scoreboard`, :mod:`skinhil.scoring`), then onsets whose response window
   passed without one become misses;
5. events from the FIFO are encoded in filled frames into the transmit queue while it
   holds less than ``tx_target_s`` of wire time (:meth:`Board._fill`: the tick is the flush
   period); each ground-truth marker follows every event before its time; a status record
   every ``status_period_s``;
6. the transmit queue goes to the transport within the wire budget
   (:class:`firmware_sim.link.BoardLink`).

A bad command never stops the board: it gets a NACK with a reason. When the link goes away
the board says so (``on_link`` callback) and either stops with
:class:`skinhil.errors.TransportError` or, with ``reconnect``, keeps its clock running,
drops events as ``link_down`` and reopens the link every ``reconnect_period_s``.
"""

from __future__ import annotations

import collections
import dataclasses
import gc
import logging
import math
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import protocols
from firmware_sim.clock import TickClock, tighten_timer_slack
from firmware_sim.command_budget import (
    ANSWER_BURST,
    PENDING_COMMANDS,
    RECORDS_PER_TICK,
    CommandBudget,
)
from firmware_sim.counters import BoardCounters
from firmware_sim.fifo import EventFifo
from firmware_sim.link import BoardLink
from protocols.versions import wire_version
from skinhil.errors import ConfigError, TransportError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.neurons import MAX_SNR_DB, MIN_SNR_DB, NoiseParams, check_threads
from skinhil.model.pipeline import SensorPipeline
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import DEFAULT_AMPLITUDE, SkinModel, SkinParams
from skinhil.model.stimuli import Schedule, ScheduledStimulus
from skinhil.model.stimulus_table import stimulus_table
from skinhil.model.timeline import MarkerEvent, Timeline
from skinhil.plant import GraspParams, HeldObject
from skinhil.scoring import DecisionScoreboard, TaskScoreboard, answer_reason
from skinhil.tasks import registry as task_registry
from skinhil.tasks import tasks_mask
from skinhil.transports import Transport
from skinhil.world import Scene, TouchSensor, TruthLog

log = logging.getLogger(__name__)

HOUSEKEEPING_SLACK_S = 5e-4
"""Work that is not part of a tick (extending the schedule, the live status callback) runs
only when the next tick is due at least this far (s) ahead."""
REALTIME_SPIN_S = 3e-4
"""Spin before each tick under ``serve --realtime`` (s). Measured on the 2-core VM, 9600-baud
pty, 4 s: without it 64-111 missed ticks of 4,000 and lateness p99 1.5-8.9 ms (wake-ups from
sleep delayed by the hypervisor now and then); with it 13-38 and p99 0.04-0.28 ms, for 20
points more of one core (35 % to 55 %)."""
SWITCH_INTERVAL_S = 2e-4
"""Python's thread switch interval (s) while the board runs (default 5 ms): a transport's
reader thread never holds the interpreter lock for longer than this against the tick."""


DEFAULT_RESPONSE_WINDOW_S = 0.5
MAX_TRUTH_MARKERS = 1_000_000
"""Markers :attr:`Board.truth_markers` keeps (about 100 MB at most)."""
"""Default response window (s) of the board's scoreboard (``serve --response-window``)."""


def _is_query(cmd: Any) -> bool:
    """Whether a host command is a QUERY_STATUS (never refused, needs no budget)."""
    return (not isinstance(cmd, protocols.Decision)
            and cmd.opcode == protocols.CommandCode.QUERY_STATUS)


@dataclass(frozen=True)
class BoardConfig:
    """Board parameters (times in s, rates in events or bits per s)."""

    dt_s: float = 1e-4
    """Simulation step (s); also the timestamp resolution."""
    tick_s: float = 1e-3
    """Publish tick (s): a whole number of steps."""
    fifo_events: int = 16384
    """Event FIFO capacity (events)."""
    status_period_s: float = 0.1
    """Status/heartbeat period (s)."""
    spin_s: float = 0.0
    """The last part (s) of each wait for a tick spent polling the clock, not asleep
    (:class:`firmware_sim.clock.TickClock`); ``serve --realtime`` uses
    :data:`REALTIME_SPIN_S`."""
    tx_target_s: float = 2e-3
    """Encoded data kept ready in the transmit queue (s of wire time)."""
    snr_db: float = math.inf
    """Neuron noise SNR (dB; inf: none)."""
    noise: NoiseParams = field(default_factory=NoiseParams)
    """How the SNR becomes neuron noise (the SET_SNR command changes only the level)."""
    seed: int = 0
    """Seed of the noise and of the default random schedule."""
    board_id: int = 0
    """Board id on a CAN bus (in the arbitration ids)."""
    mechanics: str = "auto"
    """The skin's mechanics: "auto" (geometric up to 10x10, linear above), "linear" or
    "geometric" (:class:`skinhil.model.skin.SkinParams`)."""
    readout: str = "length"
    """What each spring reports: "length" (its length change) or "axial"."""
    amplitude: str = DEFAULT_AMPLITUDE
    """The skin's regime: "small" (the default) or "paper" (the paper's: M, K and C x0.01;
    :data:`skinhil.model.skin.AMPLITUDES`)."""
    size: MeshSize = PAPER_SIZE
    """The skin's top layer (rows, cols) of masses; 6x6 is the paper's 338-channel skin."""
    threads: int = 1
    """Threads the model runs on. 1: mechanics then neurons, each tick. N > 1: the mechanics
    on the board's thread and the neurons on N − 1 others, two ticks behind
    (:class:`skinhil.model.pipeline.SensorPipeline`); pays off from a few thousand channels, where
    one core cannot keep real time."""
    schedule_mode: int = Timeline.SCHEDULE_RANDOM
    """0: host-driven only, 1: default random schedule, 2: schedule file."""
    rest_s: float = 0.25
    """Rest (s) after each stimulus of the default random schedule."""
    start_running: bool = True
    """Stream from the start (False: wait for a START command)."""
    reconnect: bool = False
    reconnect_period_s: float = 0.5
    drain_timeout_s: float = 5.0
    """At the end, how long (s) the FIFO may take to drain onto the wire."""
    response_window_s: float = DEFAULT_RESPONSE_WINDOW_S
    """How long (s) after a stimulus onset a DECISION may arrive and still answer it."""
    markers: bool = True
    """Send the ground-truth MARKERs on the link. False: the **blind link** (SPEC.md §3.4):
    no byte of truth reaches the decoder; the markers go to :attr:`Board.truth_markers`
    only (``serve --score`` without ``--markers``)."""

    @property
    def steps_per_tick(self) -> int:
        return int(round(self.tick_s / self.dt_s))

    def check(self) -> BoardConfig:
        """Return self if consistent, else raise :class:`ConfigError`."""
        if not (math.isfinite(self.dt_s) and self.dt_s > 0):
            raise ConfigError(f"step must be a positive number of seconds, got {self.dt_s!r}")
        us = self.dt_s * 1e6
        if abs(us - round(us)) > 1e-6 or round(us) < 1:
            raise ConfigError(f"step {self.dt_s!r} s is not a whole number of microseconds")
        n = self.tick_s / self.dt_s
        if not (math.isfinite(n) and n >= 1 and abs(n - round(n)) < 1e-6):
            raise ConfigError(f"tick {self.tick_s!r} s must be a whole number (>= 1) of "
                              f"steps of {self.dt_s!r} s")
        if self.fifo_events < 1:
            raise ConfigError(f"FIFO capacity must be >= 1 event, got {self.fifo_events!r}")
        if not self.status_period_s > 0:
            raise ConfigError("status period must be > 0 s")
        if not 0 <= self.spin_s < self.tick_s:
            raise ConfigError(f"spin {self.spin_s!r} s must lie in [0, tick {self.tick_s!r} s)")
        check_threads(self.threads)
        if not (math.isfinite(self.response_window_s) and self.response_window_s > 0):
            raise ConfigError(f"response window (--response-window) {self.response_window_s!r}"
                              " is not a positive number of seconds: give one such as 0.5")
        return self


@dataclass(frozen=True)
class BoardSummary:
    """What a run did: counters, timing and link use."""

    board_time_s: float
    wall_s: float
    cpu_s: float
    generated: int
    sent: int
    dropped: int
    dropped_by: dict[str, int]
    queued: int
    ticks: int
    deadline_misses: int
    lateness_ms: dict[str, float]
    commands: int
    nacks: int
    rx_errors: int
    link_losses: int
    markers_sent: int
    markers_dropped: int
    """Ground-truth markers not sent: the board was stopped or the link was gone when they
    fell due (see :mod:`firmware_sim.counters`)."""
    units_sent: int
    """Bytes (serial) or frames (CAN) handed to the link."""
    wire_busy_s: float
    """Wire time (s) used."""
    busy: int = 0
    """Host commands refused BUSY, beyond the tick's budget
    (:mod:`firmware_sim.command_budget`)."""
    scoreboard: dict[str, Any] = field(default_factory=dict)
    """The decoder under test's scoreboard (:meth:`DecisionScoreboard.summary`)."""
    tasks: dict[str, Any] = field(default_factory=dict)
    """Its ANSWERs' scores per task (:meth:`TaskScoreboard.summary`)."""

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


class Board:
    """The emulated board over a link opened by ``open_link()``.

    ``open_link`` is called at start and again on every reconnection attempt; it returns a
    :class:`~skinhil.transports.Transport` or raises :class:`TransportError`.
    ``file_schedule`` is the schedule file's content (schedule mode 2), ``scene`` its
    contacts (:mod:`skinhil.world`), which play with it: from the moment schedule mode 2
    starts, lifted when another mode starts. The contacts' ground truth stays on the board
    (:attr:`truth`), never on the link.
    """

    def __init__(self, config: BoardConfig, open_link: Callable[[], Transport[Any]],
                 file_schedule: Schedule | None = None,
                 on_link: Callable[[str], None] | None = None,
                 scene: Scene | None = None, grasp: GraspParams | None = None) -> None:
        self.config = config.check()
        if scene is not None and config.threads > 1:
            raise ConfigError("a scenario with contacts steps the mechanics and the neurons "
                              "on one thread: give --threads 1")
        self._open_link = open_link
        self.on_link = on_link or (lambda msg: log.warning("%s", msg))
        model = SkinModel(SkinParams.at_amplitude(config.amplitude, mechanics=config.mechanics,
                                                  readout=config.readout, size=config.size))
        self.sensor = SkinSensor(model, config.dt_s, config.snr_db, config.seed,
                                 noise=config.noise, threads=max(1, config.threads - 1),
                                 state_forces=scene is not None)
        self.touch = TouchSensor(self.sensor, scene) if scene is not None else None
        """The skin touching the scenario's contacts (inside the compiled step), or None."""
        if grasp is not None and self.touch is None:
            raise ConfigError("a held object needs its lifts' scene (skinhil.plant.lift_scene)")
        self.plant = (HeldObject(grasp, self.touch.world, int(round(config.tick_s * 1e6)))
                      if grasp is not None and self.touch is not None else None)
        """The held object the GRIP commands act on (its lifts are ``scene``), or None."""
        self.truth = TruthLog()
        """The contacts' ground truth, one record per contact per tick (the board's secret:
        for scoring and recordings, never sent on the link)."""
        self.pipeline = SensorPipeline(self.sensor) if config.threads > 1 else None
        """The model's two stages on their own threads (``threads`` > 1), else None."""
        log.info("board %d: %dx%d skin, %d channels, model on %d thread(s)", config.board_id,
                 model.size[0], model.size[1], model.n_springs, config.threads)
        if scene is not None and file_schedule is None:
            file_schedule = Schedule(())  # contacts only
        if file_schedule is not None:
            model.check_schedule(file_schedule)  # no force on a fixed mass, lost unsaid
        self.timeline = Timeline(config.dt_s, file_schedule, config.seed, config.rest_s,
                                 config.schedule_mode, model.size)
        self._start_scene(config.schedule_mode, 0.0)
        self.scoreboard = DecisionScoreboard(config.response_window_s,
                                             lambda sid: sid in self.timeline.catalog)
        """The decoder under test's DECISIONs scored against the onsets the board sent."""
        self.tasks: TaskScoreboard | None = None
        """Its ANSWERs of the contact tasks scored against :attr:`truth`: with a scenario's
        contacts, which pose them (a held object's lifts pose the grasp task alone)."""
        if scene is not None and self.plant is None:
            self.tasks = TaskScoreboard(
                [c.trajectory.vibration_frequency_hz if c.trajectory.vibration_amplitude_m > 0
                 else 0.0 for c in scene.contacts], config.response_window_s)
        self.truth_markers: list[MarkerEvent] = []
        """Every marker that fell due while running with the link up, sent or (on the blind
        link) withheld: the operator's truth (``serve --truth``), the first
        :data:`MAX_TRUTH_MARKERS`."""
        self.fifo = EventFifo(config.fifo_events)
        self.counters = BoardCounters()
        self.clock = TickClock(config.tick_s, spin_s=config.spin_s)
        self.running = config.start_running
        self.link: BoardLink | None = None
        self.link_losses = 0
        self._next_link_try = 0.0
        self._dt_us = int(round(config.dt_s * 1e6))
        self._markers: list[MarkerEvent] = []
        self._next_status_us = 0
        self._status_every_us = int(round(config.status_period_s * 1e6))
        self._wire_busy_s = 0.0
        self._units_sent = 0
        self.snr_db = float(config.snr_db)
        """The neuron noise level now (dB; SET_SNR changes it): what SESSION records say."""
        self.end_reason = protocols.RunEndReason.STOP
        """What the RUN_END record says when :meth:`run` ends on its ``stop`` event (the CLI
        sets SIGNAL when a signal set it)."""
        self._statuses_owed = 0
        """QUERY_STATUS answered this tick (their STATUS: after the first, at the end)."""
        self._pending: collections.deque[tuple[Any, int]] = collections.deque()
        """Host commands received and not yet executed, with their arrival (µs): at most
        :data:`~firmware_sim.command_budget.PENDING_COMMANDS`."""
        self.link = self._make_link(open_link())

    # -- link ---------------------------------------------------------------------------
    def _make_link(self, transport: Transport[Any]) -> BoardLink:
        link = BoardLink(transport, self.config.board_id,
                         fd=bool(getattr(transport, "fd", False)),
                         allowance_s=self.config.tick_s, step_us=self._dt_us,
                         n_channels=self.sensor.model.n_springs)
        self._budget = CommandBudget(self.config.tick_s, link.answer_wire_s)
        return link

    def _lose_link(self, exc: Exception) -> None:
        self.link_losses += 1
        if self.link is not None:
            self._wire_busy_s += self.link.pacer.busy_s
            self._units_sent += self.link.units_sent
            self.link.shutdown()
        self.link = None
        self.counters.drop("link_down", self.fifo.clear())
        self._drop_markers(self._markers)
        if not self.config.reconnect:
            raise TransportError(f"{exc}; start again, or use --reconnect to wait for the "
                                 "link to return") from None
        self.on_link(f"link lost ({exc}); reconnecting every "
                     f"{self.config.reconnect_period_s:g} s")
        self._next_link_try = time.monotonic() + self.config.reconnect_period_s

    def _try_reconnect(self) -> None:
        now = time.monotonic()
        if now < self._next_link_try:
            return
        self._next_link_try = now + self.config.reconnect_period_s
        try:
            transport = self._open_link()
        except TransportError as exc:
            log.debug("reconnect: %s", exc)
            return
        self.link = self._make_link(transport)
        self._next_status_us = 0
        self.queue_session(self.link, protocols.SessionReason.RECONNECT)
        self.on_link(f"link back: {transport.name}")

    # -- records ------------------------------------------------------------------------
    def board_time_us(self) -> int:
        """Board time (µs): the end of the last step whose spikes are out (with a pipeline,
        two ticks behind the mechanics)."""
        steps = self.sensor.step_index if self.pipeline is None else self.pipeline.spike_index
        return steps * self._dt_us

    def status(self) -> Any:
        """The current counters as a :class:`protocols.Status` record."""
        c = self.counters
        values: dict[str, Any] = {
            "t_us": self.board_time_us(), "events_generated": c.generated,
            "events_sent": c.sent, "events_dropped": c.dropped,
            "events_queued": len(self.fifo), "late_ticks": self.clock.deadline_misses,
            "rx_errors": c.rx_errors, "running": self.running,
        }
        for reason, n in c.dropped_by.items():
            values[f"dropped_{reason}"] = n
        return protocols.Status(**values, markers_sent=c.markers_sent,
                                markers_dropped=c.markers_dropped)

    def stimulus_table(self) -> list[Any]:
        """The stimulus table (:class:`protocols.StimulusEntry`, ascending ids): every id a
        MARKER or a SET_STIMULUS may carry, with its name."""
        return stimulus_table(self.timeline.catalog)

    def session(self, reason: Any) -> Any:
        """The :class:`protocols.Session` record of this board now, sent for ``reason``."""
        table = self.stimulus_table()
        size = self.sensor.model.size
        link = self.link
        return protocols.Session(
            t_us=self.board_time_us(), reason=reason,
            version=link.encoder.version if link is not None else wire_version(
                self.sensor.model.n_springs),
            board_id=self.config.board_id, running=self.running,
            n_channels=self.sensor.model.n_springs, rows=size[0], cols=size[1],
            step_us=self._dt_us, tick_us=int(round(self.config.tick_s * 1e6)),
            snr_db=self.snr_db,
            response_window_us=int(round(self.config.response_window_s * 1e6)),
            n_stimuli=len(table), table_digest=protocols.table_digest(table),
            tasks=self.posed_tasks(), blind=not self.config.markers)

    def posed_tasks(self) -> int:
        """The tasks whose ANSWERs this board scores, bit n for task n (SPEC.md §3.7):
        classification always (a DECISION's), the contact tasks a scenario poses."""
        return tasks_mask([protocols.Task.CLASSIFICATION,
                           *(self.tasks.tasks if self.tasks else ())])

    def queue_session(self, link: BoardLink, reason: Any) -> None:
        """Queue a SESSION record and the stimulus table's STIMULUS records (SPEC.md §3.7)."""
        link.queue_record(self.session(reason))
        for entry in self.stimulus_table():
            link.queue_record(entry)

    def _send_markers(self, link: BoardLink, before_us: int | None) -> None:
        """Queue the due ground-truth markers with ``t_us <= before_us`` (all if None): every
        event before a marker's time is on the wire ahead of it."""
        while self._markers and (before_us is None or self._markers[0].t_us <= before_us):
            m = self._markers.pop(0)
            phase = (protocols.MarkerPhase.ONSET if m.phase == "onset"
                     else protocols.MarkerPhase.END)
            link.queue_record(protocols.Marker(t_us=m.t_us, stimulus_id=m.stimulus_id,
                                               phase=phase))
            self.counters.markers_sent += 1

    def _drop_markers(self, markers: list[MarkerEvent]) -> None:
        """``markers`` will never be sent (board stopped, link gone): count them, forget them."""
        self.counters.markers_dropped += len(markers)
        markers.clear()

    # -- commands -----------------------------------------------------------------------
    def handle(self, cmd: Any, arrival_us: int | None = None) -> Any:
        """Execute a host command received at board time ``arrival_us`` (µs; default now);
        return its :class:`protocols.Ack` (never raises).

        SET_SCHEDULE numbers: 0 none (host-driven), 1 the default random schedule,
        2 the schedule file. SET_STIMULUS takes a stimulus id (0..8 direction conditions,
        10..14 paper stimuli A-E, 100.. stimuli of the schedule file).
        """
        codes, why = protocols.CommandCode, protocols.NackReason
        now_s = self.sensor.step_index * self._dt_us * 1e-6  # the mechanics' next step
        self.counters.commands += 1
        op = cmd.opcode
        reason = why.NONE
        try:
            if isinstance(cmd, protocols.Decision):
                reason = self._score(cmd, self.board_time_us() if arrival_us is None
                                     else arrival_us)
            elif isinstance(cmd, protocols.Answer):
                reason = self._score_answer(cmd, self.board_time_us() if arrival_us is None
                                            else arrival_us)
            elif op == codes.START:
                self.running = True
            elif op == codes.STOP:
                self.running = False
            elif op == codes.SET_STIMULUS:
                stim = self.timeline.catalog.get(int(cmd.arg))
                if stim is not None:  # a force on a fixed mass: BAD_ARGUMENT
                    self.sensor.model.check_stimulus(stim)
                if not self.timeline.start_stimulus(int(cmd.arg), now_s):
                    reason = why.UNKNOWN_STIMULUS
            elif op == codes.SET_SCHEDULE:
                if not self.timeline.start_schedule(int(cmd.arg), now_s):
                    reason = why.UNKNOWN_SCHEDULE
                else:
                    self._start_scene(int(cmd.arg), now_s)
            elif op == codes.SET_SNR:
                snr = float(cmd.arg)
                if not (snr == math.inf or MIN_SNR_DB <= snr <= MAX_SNR_DB):
                    reason = why.BAD_ARGUMENT  # documented range: SPEC.md §3.6
                else:
                    (self.sensor if self.pipeline is None else self.pipeline).set_snr(snr)
                    self.snr_db = snr
            elif op == codes.GRIP:
                reason = self._grip(cmd, arrival_us)
            elif op in (codes.QUERY_STATUS, codes.QUERY_SESSION, codes.PING):
                pass  # QUERY_STATUS / QUERY_SESSION: the record follows the ACK
            else:
                reason = why.UNKNOWN_COMMAND
        except (ValueError, TypeError, OverflowError, ConfigError) as exc:
            log.info("command %r rejected: %s", cmd, exc)
            reason = why.BAD_ARGUMENT
        except Exception as exc:  # a bad command never stops the board
            log.warning("command %r failed: %s", cmd, exc)
            reason = why.INTERNAL_ERROR
        ok = reason == why.NONE
        if not ok:
            self.counters.nacks += 1
            self.counters.rx_errors += 1  # a refused command shows in the next STATUS
        return protocols.Ack(token=cmd.token, opcode=op, ok=ok, reason=reason)

    def _grip(self, cmd: Any, arrival_us: int | None) -> Any:
        """A GRIP executed now (the held object's grip from the next tick on): its NACK
        reason (SPEC.md §3.5.6)."""
        why = protocols.NackReason
        if self.plant is None:
            return why.NO_OBJECT
        outcome = self.plant.set_grip(float(cmd.arg), self.board_time_us(), arrival_us,
                                      cmd.token)
        return {"ok": why.NONE, "bad_argument": why.BAD_ARGUMENT}.get(outcome, why.GRIP_LIMIT)

    def _start_scene(self, mode: int, now_s: float) -> None:
        """The contacts play from ``now_s`` (s) with the schedule file (mode 2), else none;
        the held object's grip and lifts start again with them."""
        if self.plant is not None:
            self.plant.reset()
        if self.touch is not None:
            if mode == Timeline.SCHEDULE_FILE:
                self.touch.start(now_s)
            else:
                self.touch.stop()

    def _execute(self, link: BoardLink, cmd: Any, arrival_us: int | None = None) -> None:
        """Execute a host command received at board time ``arrival_us`` (µs) and queue its
        ACK (a QUERY_SESSION's SESSION after it)."""
        link.queue_record(self.handle(cmd, arrival_us))
        if (not isinstance(cmd, protocols.Decision)
                and cmd.opcode == protocols.CommandCode.QUERY_SESSION):
            self.queue_session(link, protocols.SessionReason.REQUEST)

    def _refuse_busy(self, link: BoardLink, keys: list[tuple[int, int]], n: int) -> None:
        """``n`` commands beyond the tick's budget (:mod:`firmware_sim.command_budget`), the
        first of them (token, opcode) ``keys``: not executed, counted (``busy``, ``nacks``,
        ``rx_errors``); NACKed BUSY in order while the answer bucket has room."""
        c = self.counters
        c.commands += n
        c.busy += n
        c.nacks += n
        c.rx_errors += n
        for token, opcode in keys:
            if not self._budget.answer_busy():
                return
            link.queue_record(protocols.Ack(token=token, opcode=opcode, ok=False,
                                            reason=protocols.NackReason.BUSY))

    def _answer_query(self, link: BoardLink, cmd: Any, t_end_us: int) -> None:
        """Execute and ACK a QUERY_STATUS (never refused): the tick's first is followed by a
        STATUS at once, any later one by a STATUS at the end of the tick (two at most)."""
        self._budget.admit_query()
        link.queue_record(self.handle(cmd))
        self._statuses_owed += 1
        if self._statuses_owed == 1:
            self._fill(link, t_end_us)
            link.queue_record(self.status())

    def _refuse_excess(self, link: BoardLink, excess: np.ndarray, t_end_us: int) -> None:
        """The commands the link did not build into records (past :data:`RECORDS_PER_TICK`):
        each QUERY_STATUS answered, the others refused BUSY."""
        query = excess["opcode"] == protocols.CommandCode.QUERY_STATUS
        for token in excess["token"][query].tolist():
            self._answer_query(link, protocols.Command(token, protocols.CommandCode.QUERY_STATUS),
                               t_end_us)
        rest = excess[~query]
        if rest.shape[0]:
            self._refuse_busy(link, rest[:int(ANSWER_BURST)].tolist(), rest.shape[0])

    def _score(self, decision: Any, t_us: int) -> Any:
        """Stamp a DECISION with its arrival's board time ``t_us`` (µs) and score it; its
        NACK reason (NONE when scored, NOT_RUNNING while stopped, UNKNOWN_STIMULUS for an id
        the board does not know: counted all the same)."""
        outcome = self.scoreboard.decision(decision.stimulus_id, t_us,
                                           decision.confidence, self.running, decision.token)
        log.debug("decision %r: %s", decision, outcome.value)
        return answer_reason(outcome)

    def _score_answer(self, answer: Any, t_us: int) -> Any:
        """Score an ANSWER arriving at board time ``t_us`` (µs), SPEC.md §3.5.3: a
        CLASSIFICATION as a DECISION without confidence, the contact tasks against the truth
        (:attr:`tasks`); its NACK reason (UNKNOWN_TASK, TASK_NOT_POSED: counted too)."""
        task = int(answer.task)
        if task == protocols.Task.CLASSIFICATION:
            return self._score(protocols.Decision(answer.token, int(answer.values[0])), t_us)
        if task_registry.task(task) is None:
            return protocols.NackReason.UNKNOWN_TASK
        if self.tasks is None or not self.tasks.posed(task):
            if self.tasks is not None:
                self.tasks.not_posed[task] += 1
            return protocols.NackReason.TASK_NOT_POSED
        outcome = self.tasks.answer(answer, t_us, self.running)
        log.debug("answer %r: %s", answer, outcome)
        return (protocols.NackReason.NOT_RUNNING if outcome == "while_stopped"
                else protocols.NackReason.NONE)

    # -- one tick -----------------------------------------------------------------------
    def tick(self) -> None:
        """Run one publish tick (see module docstring for the order)."""
        spikes, first = self.step_model()
        if not self._publish(spikes, first):
            self._try_reconnect()
            return
        try:
            self._serve_link(self.board_time_us())
        except TransportError as exc:
            self._lose_link(exc)
        self.scoreboard.advance(self.board_time_us())
        if self.tasks is not None:
            self.tasks.advance(self.board_time_us())

    def step_model(self) -> tuple[np.ndarray, int]:
        """The model's steps of one tick (the held object's grip applied before, its truth,
        the contacts' and the task trials' kept after): the spikes (steps, channels) and their
        first step."""
        cfg = self.config
        first = self.sensor.step_index
        n = cfg.steps_per_tick
        if self.touch is not None:  # the schedule's and the contacts' forces, compiled
            if self.plant is not None:
                self.plant.before_tick()
            schedule = self.timeline.schedule_for(first * cfg.dt_s, (first + n - 1) * cfg.dt_s)
            _, spikes, raw = self.touch.advance_schedule(schedule, n)
            self.truth.add_raw(first * self._dt_us, raw[0])
            if self.tasks is not None and self.running and self.link is not None:
                self.tasks.observe(first * self._dt_us, raw[0])
            if self.plant is not None:
                self.truth.add_object(self.plant.after_tick(
                    first * self._dt_us, first * cfg.dt_s - self.touch.scene_offset_s,
                    cfg.dt_s, raw))
        elif self.pipeline is None:  # the schedule's forces made inside the compiled step
            schedule = self.timeline.schedule_for(first * cfg.dt_s, (first + n - 1) * cfg.dt_s)
            _, spikes = self.sensor.advance_schedule(schedule, n)
        else:
            spikes, first = self.pipeline.advance(
                self.timeline.forces((first + np.arange(n)) * cfg.dt_s))
        return spikes, first

    def _publish(self, spikes: np.ndarray, first: int) -> bool:
        """The events of a spike block starting at step ``first`` counted as generated and
        pushed into the FIFO (or dropped by reason), the markers due by the board time
        queued (or dropped); False when there is no link."""
        t_end_us = self.board_time_us()
        events = self.sensor.events(spikes, first)
        c = self.counters
        c.generated += len(events)
        if self.link is None:
            c.drop("link_down", len(events))
        elif not self.running:
            c.drop("stopped", len(events))
        else:
            c.drop("fifo_full", self.fifo.push(events))
        markers = self.timeline.markers_before(t_end_us)
        if self.link is None:
            self._drop_markers(markers)
            return False
        if self.running:
            if self.config.markers:
                self._markers.extend(markers)
            if len(self.truth_markers) < MAX_TRUTH_MARKERS:
                self.truth_markers.extend(markers)
            for m in markers:  # the ground truth the decoder under test is scored against
                if m.phase == "onset":
                    self.scoreboard.onset(m.stimulus_id, m.t_us)
        else:
            self._drop_markers(markers)
        return True

    def _serve_link(self, t_end_us: int) -> None:
        link = self.link
        assert link is not None
        pending = self._pending
        room = PENDING_COMMANDS - len(pending)
        commands, excess = link.poll_commands(max(RECORDS_PER_TICK, room))
        self.counters.rx_errors += link.take_rx_errors()
        budget = self._budget
        budget.new_tick()
        self._statuses_owed = 0
        for cmd in commands:
            if len(pending) < PENDING_COMMANDS:
                pending.append((cmd, t_end_us))  # a burst waits its turn, its arrival kept
            elif _is_query(cmd):  # never refused: answered at once when the queue is full
                self._answer_query(link, cmd, t_end_us)
            else:
                self._refuse_busy(link, [(cmd.token, int(cmd.opcode))], 1)
        if excess.shape[0]:
            self._refuse_excess(link, excess, t_end_us)
        while pending:  # in arrival order: a QUERY_STATUS needs no budget, the others do
            cmd, arrival_us = pending[0]
            if _is_query(cmd):
                self._answer_query(link, cmd, t_end_us)
            elif budget.admit():
                self._execute(link, cmd, arrival_us)
            else:
                break
            pending.popleft()
        if self._statuses_owed > 1:  # one more STATUS answers the later QUERY_STATUS
            self._fill(link, t_end_us)
            link.queue_record(self.status())
        if t_end_us >= self._next_status_us and link.backlog_s() < self.config.tx_target_s:
            # the heartbeat waits while the link is saturated: it never piles up
            self._fill(link, t_end_us)
            link.queue_record(self.status())
            self._next_status_us = t_end_us + self._status_every_us
        self._fill(link, t_end_us)
        link.pump()

    def _fill(self, link: BoardLink, t_end_us: int) -> None:
        """Encode the FIFO's events in filled frames, and the due markers, while the
        transmit queue holds less than ``tx_target_s`` of wire time.

        Everything queued goes when it fits: the last frame closes after the last event
        generated (the flush, every tick). When the FIFO holds more than the queue has room
        for, the encoder writes only whole frames, as many as the room takes (rounded up:
        the queue may pass its target by less than one frame), and the events left wait for
        the next call, so a backlog leaves in full frames. A marker is queued once every
        event before its time is, so it may follow its events by up to one batch.
        """
        target = self.config.tx_target_s
        while True:
            head = self.fifo.peek_time_us()
            self._send_markers(link, head)
            if head is None:
                if self.running:  # an empty call: keeps the time base alive (SYNC)
                    link.queue_events(self.fifo.pop(0), t_end_us)
                return
            room = target - link.backlog_s()
            if room <= 0:
                return
            frames = max(1, math.ceil(room / link.frame_s))
            n = len(self.fifo)
            if n > frames * link.frame_events:  # a batch never splits a step
                n = self.fifo.count_before(self.fifo.time_at(frames * link.frame_events - 1)
                                           + self._dt_us)
            batch = self.fifo.peek(n)
            end = t_end_us if n == len(self.fifo) else self.fifo.time_at(n)
            used = link.queue_events(batch, end, frames)
            self.fifo.pop(used)
            self.counters.sent += used

    # -- run ----------------------------------------------------------------------------
    def run(self, duration_s: float | None = None, stop: threading.Event | None = None,
            on_second: Callable[[Board], None] | None = None,
            report_period_s: float = 0.5) -> BoardSummary:
        """Run in real time until ``duration_s`` of board time or ``stop`` is set.

        ``on_second(board)`` is called every ``report_period_s`` of wall time (for live
        status), in a tick's spare time; when the board is overloaded and no tick has spare
        time it is called anyway once a call is one period overdue, so at least every
        ``2 * report_period_s``. The run opens with the SESSION record and the stimulus
        table; at the end the FIFO drains onto the wire (at most ``drain_timeout_s``), a
        final status and the RUN_END record (DURATION, or :attr:`end_reason` when ``stop``
        ended it; ERROR after an internal error) are sent and the link is closed. Raises
        :class:`TransportError` when the link goes away without ``reconnect``.
        """
        stop = stop or threading.Event()
        self.warm_up()
        tighten_timer_slack()
        gc.collect()
        gc.freeze()
        switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL_S)
        cpu0, wall0 = time.process_time(), time.monotonic()
        n_ticks = None if duration_s is None else int(round(duration_s / self.config.tick_s))
        next_report = wall0 + report_period_s
        if self.link is not None:
            self.queue_session(self.link, protocols.SessionReason.START)
        reason = protocols.RunEndReason.DURATION
        self.clock.start()
        try:
            while not stop.is_set() and (n_ticks is None or self.clock.index < n_ticks):
                self.clock.wait()
                self.tick()
                self.clock.done()
                if self.clock.slack_s() > HOUSEKEEPING_SLACK_S:
                    self.timeline.prepare(self.board_time_us() * 1e-6)
                now = time.monotonic()
                if on_second is not None and now >= next_report:
                    # live status in a tick's spare time; an overloaded board has none
                    overdue = now >= next_report + report_period_s
                    if overdue or self.clock.slack_s() > HOUSEKEEPING_SLACK_S:
                        next_report = (now if overdue else next_report) + report_period_s
                        on_second(self)
            if stop.is_set():
                reason = self.end_reason
            self._finish(reason)
        except TransportError:
            raise
        except Exception:
            self._finish_after_error()
            raise
        finally:
            sys.setswitchinterval(switch_interval)
            if self.link is not None:
                self._wire_busy_s += self.link.pacer.busy_s
                self._units_sent += self.link.units_sent
                self.link.shutdown()
                self.link = None
        return self.summary(time.monotonic() - wall0, time.process_time() - cpu0)

    def _finish_after_error(self) -> None:
        """After an internal error: still try to close the account and say ERROR on the
        wire (RUN_END), so a receiver does not take the silence for a dead link."""
        try:
            self._finish(protocols.RunEndReason.ERROR)
        except Exception as exc:  # the error being raised is the one to report
            log.warning("could not finish the run after an error: %s", exc)

    def warm_up(self) -> None:
        """Run the model and every link code path once off the clock (compiles or loads the
        numba kernels: a cold compile inside a tick is a stall of about a second), then
        reset the model to rest with its noise streams where they were: the board then
        plays exactly what the same seed gives offline
        (:func:`skinhil.receiver.training.board_stream`)."""
        if self.sensor.step_index:
            return
        streams = self.sensor.neurons.noise_streams()
        n = self.config.steps_per_tick
        t_s = np.arange(n) * self.config.dt_s
        if self.touch is not None:  # the contact kernel compiled or loaded
            self.touch.start(0.0)
            self.touch.advance_schedule(self.timeline.schedule_for(t_s[0], t_s[-1]), n)
        elif self.pipeline is None:
            self.sensor.advance_schedule(self.timeline.schedule_for(t_s[0], t_s[-1]), n)
        else:
            for _ in range(2):  # the second call starts the neurons on the first block
                self.pipeline.advance(self.timeline.forces(t_s))
        for entry in self.timeline.schedule.entries[:1]:  # a stimulus while it is active
            Schedule((ScheduledStimulus(0.0, entry.stimulus, 0),)).force_at(
                t_s, entry.stimulus.size)
        self.sensor.events(np.zeros((n, self.sensor.model.n_springs), dtype=bool), 0)
        (self.sensor if self.pipeline is None else self.pipeline).reset()  # waits for them
        self.sensor.neurons.restore_noise_streams(streams)
        if self.touch is not None:
            self.truth.clear()
            self._start_scene(self.timeline.mode, 0.0)
        if self.link is not None:
            self.link.warm_up(self.status())

    def _finish(self, reason: Any = protocols.RunEndReason.DURATION) -> None:
        """Publish the spikes still in the pipeline (``threads`` > 1), then drain the FIFO
        for at most ``drain_timeout_s``, count what is left as dropped at
        ``shutdown``, queue the markers still due, a final status and the RUN_END record
        saying ``reason``, and send the whole
        transmit queue (it holds at most ``tx_target_s`` and one frame more, plus these
        records: events counted as sent always reach the wire)."""
        if self.pipeline is not None and self.pipeline.in_flight:
            self._publish(*self.pipeline.flush())  # the last two ticks' spikes
        link = self.link
        if link is None:
            return
        end = time.monotonic() + self.config.drain_timeout_s
        t_end_us = self.board_time_us()
        try:
            while (len(self.fifo) or self._markers) and time.monotonic() < end:
                self._fill(link, t_end_us)
                link.pump()
                time.sleep(self.config.tick_s / 4)
            self.counters.drop("shutdown", self.fifo.clear())
            self._send_markers(link, None)  # ground truth is never left behind with events
            link.queue_record(self.status())
            link.queue_record(protocols.RunEnd(t_us=self.board_time_us(), reason=reason))
            link.drain(max(0.5, end - time.monotonic(), 2 * link.backlog_s() + 0.5))
            link.wait_wire_idle(1.0)
        except TransportError as exc:
            log.warning("link lost while finishing: %s", exc)
            self._drop_markers(self._markers)

    def summary(self, wall_s: float = 0.0, cpu_s: float = 0.0) -> BoardSummary:
        c = self.counters
        link = self.link
        return BoardSummary(
            board_time_s=self.board_time_us() * 1e-6, wall_s=wall_s, cpu_s=cpu_s,
            generated=c.generated, sent=c.sent, dropped=c.dropped,
            dropped_by=dict(c.dropped_by), queued=len(self.fifo), ticks=self.clock.ticks,
            deadline_misses=self.clock.deadline_misses,
            lateness_ms=self.clock.lateness_percentiles_ms(), commands=c.commands,
            nacks=c.nacks, rx_errors=c.rx_errors, link_losses=self.link_losses,
            markers_sent=c.markers_sent, markers_dropped=c.markers_dropped,
            units_sent=self._units_sent + (link.units_sent if link else 0),
            wire_busy_s=self._wire_busy_s + (link.pacer.busy_s if link else 0.0),
            busy=c.busy, scoreboard=self.scoreboard.summary(),
            tasks=self.tasks.summary() if self.tasks is not None else {})
