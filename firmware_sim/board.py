"""The emulated sensor board: the clock and an ordered list of participants.

Per publish tick ``k`` (default 1 ms = 10 steps of 0.1 ms), due at ``t0 + (k+1)·tick``
(:class:`firmware_sim.clock.TickClock`), the board runs the phases of
:data:`firmware_sim.tick.SCHEDULE` in order, in each the hooks of that name of
:attr:`Board.participants` in their order: the stimulus and the world, the model (one of
:mod:`firmware_sim.model_stage`), scoring, the held object, the encoder and its pacing, the
host commands, status and session, the link (``docs/architecture.md``, "The board's
tick"). A part absent (no scene, no held object) takes no part; each reaches the rest only
through the context it is handed (:class:`firmware_sim.tick.TickContext`), never the board.
"""

from __future__ import annotations

import gc
import logging
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import protocols
from firmware_sim import tick as phases
from firmware_sim.clock import TickClock, tighten_timer_slack
from firmware_sim.config import BoardConfig, BoardSummary
from firmware_sim.counters import BoardCounters
from firmware_sim.encoder_stage import Encoder
from firmware_sim.fifo import EventFifo
from firmware_sim.host_commands import HostCommands
from firmware_sim.link import BoardLink
from firmware_sim.link_keeper import LinkKeeper
from firmware_sim.model_stage import model_for
from firmware_sim.plant_stage import HeldObjectStage
from firmware_sim.scoring_stage import Scoring
from firmware_sim.status_stage import StatusReporter
from firmware_sim.tick import Participant, Phase, TickContext
from firmware_sim.world_stage import StimulusWorld
from skinhil.errors import ConfigError, TransportError
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.model.timeline import MarkerEvent, Timeline
from skinhil.plant import GraspParams, HeldObject
from skinhil.transports import Transport
from skinhil.world import Scene, TouchSensor, TruthLog

__all__ = ["Board", "BoardConfig", "BoardSummary"]

log = logging.getLogger(__name__)

HOUSEKEEPING_SLACK_S = 5e-4
"""Work that is not part of a tick (extending the schedule, the live status callback) runs
only when the next tick is due at least this far (s) ahead."""
SWITCH_INTERVAL_S = 2e-4
"""Python's thread switch interval (s) while the board runs (default 5 ms): a transport's
reader thread never holds the interpreter lock for longer than this against the tick."""


class Board:
    """The emulated board over a link opened by ``open_link()``.

    ``open_link`` is called at start and again on every reconnection attempt; it returns a
    :class:`~skinhil.transports.Transport` or raises :class:`TransportError`.
    ``file_schedule`` is the schedule file's content (schedule mode 2), ``scene`` its
    contacts (:mod:`skinhil.world`), which play with it: from the moment schedule mode 2
    starts, lifted when another mode starts. The contacts' ground truth stays on the board
    (:attr:`truth`), never on the link. ``grasp`` puts a held object on ``scene``'s lifts.
    """

    def __init__(self, config: BoardConfig, open_link: Callable[[], Transport[Any]],
                 file_schedule: Schedule | None = None,
                 on_link: Callable[[str], None] | None = None,
                 scene: Scene | None = None, grasp: GraspParams | None = None) -> None:
        self.config = config.check()
        if scene is not None and config.threads > 1:
            raise ConfigError("a scenario with contacts steps the mechanics and the neurons "
                              "on one thread: give --threads 1")
        if grasp is not None and scene is None:
            raise ConfigError("a held object needs its lifts' scene (skinhil.plant.lift_scene)")
        model = SkinModel(SkinParams.at_amplitude(config.amplitude, mechanics=config.mechanics,
                                                  readout=config.readout, size=config.size))
        self.sensor = SkinSensor(model, config.dt_s, config.snr_db, config.seed,
                                 noise=config.noise, threads=max(1, config.threads - 1),
                                 state_forces=scene is not None)
        self.touch = TouchSensor(self.sensor, scene) if scene is not None else None
        """The skin touching the scenario's contacts (inside the compiled step), or None."""
        self.plant = (HeldObject(grasp, self.touch.world, int(round(config.tick_s * 1e6)))
                      if grasp is not None and self.touch is not None else None)
        """The held object the GRIP commands act on (its lifts are ``scene``), or None."""
        self.truth = TruthLog()
        """The contacts' ground truth, one record per contact per tick (the board's secret:
        for scoring and recordings, never sent on the link)."""
        log.info("board %d: %dx%d skin, %d channels, model on %d thread(s)", config.board_id,
                 model.size[0], model.size[1], model.n_springs, config.threads)
        if scene is not None and file_schedule is None:
            file_schedule = Schedule(())  # contacts only
        if file_schedule is not None:
            model.check_schedule(file_schedule)  # no force on a fixed mass, lost unsaid
        self.timeline = Timeline(config.dt_s, file_schedule, config.seed, config.rest_s,
                                 config.schedule_mode, model.size)
        scoring = Scoring.posed_by(config.response_window_s,
                                   lambda sid: sid in self.timeline.catalog, scene, self.plant,
                                   config.tasks)
        self.scoreboard = scoring.scoreboard
        """The decoder under test's DECISIONs scored against the onsets the board sent."""
        self.tasks = scoring.tasks
        """Its ANSWERs of the contact tasks scored against :attr:`truth`, or None."""
        self.fifo = EventFifo(config.fifo_events)
        self.counters = BoardCounters()
        self.clock = TickClock(config.tick_s, spin_s=config.spin_s)
        self.ctx = TickContext(config, self.counters, self.fifo, self.clock,
                               running=config.start_running, snr_db=float(config.snr_db))
        self.end_reason = protocols.RunEndReason.STOP
        """What RUN_END says when :meth:`run` ends on its ``stop`` event (the CLI: SIGNAL)."""
        self.world = StimulusWorld(self.timeline, model, self.touch)
        self.model = model_for(self.sensor, self.timeline, self.touch, self.truth,
                               config.threads)
        self.status_reporter = StatusReporter(
            model, self.timeline, scoring.posed_tasks,
            held_object=self.plant is not None and self.touch is not None)
        self.link_keeper = LinkKeeper(open_link, model.n_springs,
                                      on_link or (lambda msg: log.warning("%s", msg)))
        held = ([HeldObjectStage(self.plant, self.touch, self.truth)]
                if self.plant is not None and self.touch is not None else [])
        self.commands = HostCommands()
        self.participants: list[Participant] = [
            self.world, self.model, scoring, *held, Encoder(self.sensor.events), self.commands,
            self.status_reporter, self.link_keeper]
        """In the order their hooks run within a phase."""
        self.commands.register(self.participants)
        self._hooks = {name: [getattr(p, name) for p in self.participants
                              if callable(getattr(type(p), name, None))] for name in phases.HOOKS}
        self._schedule: list[tuple[Phase, list[Callable[..., None]]]] = [
            (phase, self._hooks[phase.name]) for phase in phases.SCHEDULE
            if self._hooks[phase.name]]  # a phase no participant takes part in is skipped
        self._each("attach")
        self.ctx.start_scene = lambda mode, now_s: self._each("start_scene", mode, now_s)
        self.ctx.start_scene(config.schedule_mode, 0.0)
        self.link_keeper.open(self.ctx)

    def _each(self, hook: str, *args: Any) -> None:
        """Run every participant's ``hook`` with the context and ``args``."""
        for fn in self._hooks[hook]:
            fn(self.ctx, *args)

    @property
    def link(self) -> BoardLink | None:
        """The link, None while it is down."""
        return self.ctx.link

    @property
    def running(self) -> bool:
        """Whether events and markers are streamed (START / STOP)."""
        return self.ctx.running

    @property
    def truth_markers(self) -> list[MarkerEvent]:
        """Every marker that fell due while running with the link up (the operator's)."""
        return self.world.truth_markers

    def board_time_us(self) -> int:
        """Board time (µs): the end of the last step whose spikes are out."""
        return self.ctx.board_time_us()

    def status(self) -> Any:
        """The current counters as a :class:`protocols.Status` record."""
        return self.status_reporter.status(self.ctx)

    def session(self, reason: Any) -> Any:
        """The :class:`protocols.Session` record of this board now, sent for ``reason``."""
        return self.status_reporter.session(self.ctx, reason)

    def queue_session(self, reason: Any) -> None:
        """Queue a SESSION record and the stimulus table (SPEC.md §3.7)."""
        self.ctx.queue_session(reason)

    def handle(self, cmd: Any, arrival_us: int | None = None) -> Any:
        """Execute a host command received at board time ``arrival_us`` (µs; default now);
        return its :class:`protocols.Ack` (never raises)."""
        return self.commands.handle(self.ctx, cmd, arrival_us)

    def tick(self) -> None:
        """Run one publish tick: the phases of :data:`~firmware_sim.tick.SCHEDULE` in order.
        A link lost on the wire ends the wire's phases (``link_lost`` hooks)."""
        ctx = self.ctx
        for phase, hooks in self._schedule:
            if not phase.runs(ctx.serving, ctx.link is not None):
                continue
            for hook in hooks:
                try:
                    hook(ctx)
                except TransportError as exc:
                    if phase.when != "wire":
                        raise
                    self._each("link_lost", exc)
                    break

    def step_model(self) -> None:
        """The model's phases of one tick alone (:data:`~firmware_sim.tick.MODEL_PHASES`)."""
        for name in phases.MODEL_PHASES:
            self._each(name)

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
            self.queue_session(protocols.SessionReason.START)
        reason = protocols.RunEndReason.DURATION
        self.clock.start()
        try:
            while not stop.is_set() and (n_ticks is None or self.clock.index < n_ticks):
                self.clock.wait()
                self.tick()
                self.clock.done()
                if self.clock.slack_s() > HOUSEKEEPING_SLACK_S:
                    self._each("housekeeping")
                now = time.monotonic()
                if on_second is not None and now >= next_report:
                    # live status in a tick's spare time; an overloaded board has none
                    overdue = now >= next_report + report_period_s
                    if overdue or self.clock.slack_s() > HOUSEKEEPING_SLACK_S:
                        next_report = (now if overdue else next_report) + report_period_s
                        on_second(self)
            if stop.is_set():
                reason = self.end_reason
            self.finish(reason)
        except TransportError:
            raise
        except Exception:
            self._finish_after_error()
            raise
        finally:
            sys.setswitchinterval(switch_interval)
            self.link_keeper.close(self.ctx)
        return self.summary(time.monotonic() - wall0, time.process_time() - cpu0)

    def _finish_after_error(self) -> None:
        """After an internal error: still try to close the account and say ERROR on the
        wire (RUN_END), so a receiver does not take the silence for a dead link."""
        try:
            self.finish(protocols.RunEndReason.ERROR)
        except Exception as exc:  # the error being raised is the one to report
            log.warning("could not finish the run after an error: %s", exc)

    def warm_up(self) -> None:
        """Run the model and every link code path once off the clock (compiles or loads the
        numba kernels: a cold compile inside a tick is a stall of about a second), then
        reset the model to rest with its noise streams where they were."""
        if self.ctx.step_index:
            return
        for name in phases.WARM_UP:
            self._each(name)

    def finish(self, reason: Any = protocols.RunEndReason.DURATION) -> None:
        """End the run (the phases of :data:`~firmware_sim.tick.FINISH`): the spikes still
        in the model published, then the FIFO drained, a final status and the RUN_END
        record saying ``reason``."""
        ctx = self.ctx
        ctx.end_reason, ctx.spikes = reason, None
        for name in phases.FINISH:
            if name != "publish" or ctx.spikes is not None:
                self._each(name)

    def summary(self, wall_s: float = 0.0, cpu_s: float = 0.0) -> BoardSummary:
        """The run's account, with its wall and CPU time (s) as measured by the caller."""
        c = self.counters
        return BoardSummary(
            board_time_s=self.board_time_us() * 1e-6, wall_s=wall_s, cpu_s=cpu_s,
            generated=c.generated, sent=c.sent, dropped=c.dropped,
            dropped_by=dict(c.dropped_by), queued=len(self.fifo), ticks=self.clock.ticks,
            deadline_misses=self.clock.deadline_misses,
            lateness_ms=self.clock.lateness_percentiles_ms(), commands=c.commands,
            nacks=c.nacks, rx_errors=c.rx_errors, link_losses=self.link_keeper.losses,
            markers_sent=c.markers_sent, markers_dropped=c.markers_dropped,
            units_sent=self.link_keeper.units_sent(self.ctx),
            wire_busy_s=self.link_keeper.wire_busy_s(self.ctx),
            busy=c.busy, scoreboard=self.scoreboard.summary(),
            tasks=self.tasks.summary() if self.tasks is not None else {})
