"""The board's status and session: a STATUS record every ``status_period_s`` (the
heartbeat, which waits while the link is saturated), the SESSION record, the stimulus table,
the SUITE and its TASK records (SPEC.md §3.7), and the queries that ask for them."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import protocols
from firmware_sim.link import BoardLink
from firmware_sim.tick import CommandHandler, Participant, TickContext
from protocols.versions import wire_version
from skinhil.model.skin import SkinModel
from skinhil.model.stimulus_table import stimulus_table
from skinhil.model.timeline import Timeline


class StatusReporter(Participant):
    """STATUS and SESSION records of a board whose skin is ``model``, whose stimuli are
    ``timeline``'s, whose posed tasks ``posed_tasks()`` says and which holds an object
    (``held_object``) or not. The suite case and its tasks' terms it announces are the
    board's configuration's (``suite_name``, ``suite_version``, ``suite_case``,
    ``task_terms``)."""

    def __init__(self, model: SkinModel, timeline: Timeline,
                 posed_tasks: Callable[[], int], held_object: bool = False) -> None:
        self.skin = model
        self.timeline = timeline
        self.posed_tasks = posed_tasks
        self.held_object = held_object
        self._next_status_us = 0
        self._link: BoardLink | None = None
        """The link the heartbeat was timed on: a new link has its first STATUS at once."""

    def attach(self, ctx: TickContext) -> None:
        ctx.status = lambda: self.status(ctx)
        ctx.queue_session = lambda reason: self.queue_session(ctx, reason)

    def heartbeat(self, ctx: TickContext) -> None:
        link = ctx.link
        assert link is not None
        if link is not self._link:
            self._link, self._next_status_us = link, 0
        t_us = ctx.board_time_us()
        if t_us >= self._next_status_us and link.backlog_s() < ctx.config.tx_target_s:
            # the heartbeat waits while the link is saturated: it never piles up
            ctx.queue_status()
            self._next_status_us = t_us + int(round(ctx.config.status_period_s * 1e6))

    def status(self, ctx: TickContext) -> Any:
        """The current counters as a :class:`protocols.Status` record."""
        c = ctx.counters
        values: dict[str, Any] = {
            "t_us": ctx.board_time_us(), "events_generated": c.generated,
            "events_sent": c.sent, "events_dropped": c.dropped,
            "events_queued": len(ctx.fifo), "late_ticks": ctx.clock.deadline_misses,
            "rx_errors": c.rx_errors, "running": ctx.running,
        }
        for reason, n in c.dropped_by.items():
            values[f"dropped_{reason}"] = n
        return protocols.Status(**values, markers_sent=c.markers_sent,
                                markers_dropped=c.markers_dropped)

    def stimulus_table(self) -> list[Any]:
        """The stimulus table (:class:`protocols.StimulusEntry`, ascending ids): every id a
        MARKER or a SET_STIMULUS may carry, with its name."""
        return stimulus_table(self.timeline.catalog)

    def session(self, ctx: TickContext, reason: Any) -> Any:
        """The :class:`protocols.Session` record of this board now, sent for ``reason``."""
        cfg = ctx.config
        table = self.stimulus_table()
        size = self.skin.size
        link = ctx.link
        return protocols.Session(
            t_us=ctx.board_time_us(), reason=reason,
            version=link.encoder.version if link is not None else wire_version(
                self.skin.n_springs),
            board_id=cfg.board_id, running=ctx.running,
            n_channels=self.skin.n_springs, rows=size[0], cols=size[1],
            step_us=ctx.dt_us, tick_us=int(round(cfg.tick_s * 1e6)),
            snr_db=ctx.snr_db,
            response_window_us=int(round(cfg.response_window_s * 1e6)),
            n_stimuli=len(table), table_digest=protocols.table_digest(table),
            tasks=self.posed_tasks(), blind=not cfg.markers, held_object=self.held_object)

    def suite_records(self, ctx: TickContext) -> list[Any]:
        """The SUITE record (no suite: empty names) and the TASK records of the terms it
        announces (:class:`protocols.SuiteEntry`, :class:`protocols.TaskEntry`)."""
        cfg = ctx.config
        return [protocols.SuiteEntry(cfg.suite_name, cfg.suite_version, cfg.suite_case,
                                     len(cfg.task_terms)), *cfg.task_terms]

    def queue_session(self, ctx: TickContext, reason: Any) -> None:
        """Queue a SESSION record, the stimulus table's STIMULUS records, the SUITE and its
        TASK records (SPEC.md §3.7)."""
        ctx.queue_record(self.session(ctx, reason))
        for entry in (*self.stimulus_table(), *self.suite_records(ctx)):
            ctx.queue_record(entry)

    def commands(self) -> dict[int, CommandHandler]:
        codes = protocols.CommandCode
        return dict.fromkeys((codes.QUERY_STATUS, codes.QUERY_SESSION, codes.PING), _answered)


def _answered(ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
    """A query: ACKed (a QUERY_STATUS's STATUS, a QUERY_SESSION's SESSION follow it)."""
    return protocols.NackReason.NONE
