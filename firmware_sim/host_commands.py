"""The host's commands: received from the link each tick, executed in arrival order within
the tick's budget (:mod:`firmware_sim.command_budget`) by the handlers the participants
register (opcode → handler), each answered with an ACK or a NACK saying why.

A bad command never stops the board: it gets a NACK with a reason. START and STOP, which
set the running flag every participant reads, are handled here.
"""

from __future__ import annotations

import collections
import logging
from collections.abc import Iterable
from typing import Any

import numpy as np

import protocols
from firmware_sim.command_budget import (
    ANSWER_BURST,
    PENDING_COMMANDS,
    CommandBudget,
)
from firmware_sim.link import BoardLink
from firmware_sim.tick import CommandHandler, Participant, TickContext
from skinhil.errors import ConfigError

log = logging.getLogger(__name__)


_QUERY_STATUS = int(protocols.CommandCode.QUERY_STATUS)
"""QUERY_STATUS's opcode as a plain int (compared with a whole array of opcodes)."""


def _is_query(cmd: Any) -> bool:
    """Whether a host command is a QUERY_STATUS (never refused, needs no budget)."""
    return (not isinstance(cmd, protocols.Decision)
            and cmd.opcode == protocols.CommandCode.QUERY_STATUS)


def _no_object(ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
    """GRIP on a board without a held object."""
    return protocols.NackReason.NO_OBJECT


def _start(ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
    ctx.running = True
    return protocols.NackReason.NONE


def _stop(ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
    ctx.running = False
    return protocols.NackReason.NONE


class HostCommands(Participant):
    """The command intake and the dispatch table."""

    def __init__(self) -> None:
        codes = protocols.CommandCode
        self.table: dict[int, CommandHandler] = {
            codes.START: _start, codes.STOP: _stop, codes.GRIP: _no_object}
        """opcode → handler: the participants' own (:meth:`register`), over the fallbacks."""
        self._pending: collections.deque[tuple[Any, int]] = collections.deque()
        """Host commands received and not yet executed, with their arrival (µs): at most
        :data:`~firmware_sim.command_budget.PENDING_COMMANDS`."""
        self._budget: CommandBudget | None = None
        self._link: BoardLink | None = None
        self._statuses_owed = 0
        """QUERY_STATUS answered this tick (their STATUS: after the first, at the end)."""

    def register(self, owners: Iterable[Participant]) -> None:
        """Dispatch to each of ``owners`` the opcodes its ``commands()`` names."""
        for p in owners:
            self.table.update(p.commands())

    def handle(self, ctx: TickContext, cmd: Any, arrival_us: int | None = None) -> Any:
        """Execute a host command received at board time ``arrival_us`` (µs; None: now);
        return its :class:`protocols.Ack` (never raises)."""
        why = protocols.NackReason
        ctx.counters.commands += 1
        handler = self.table.get(int(cmd.opcode))
        try:
            reason = why.UNKNOWN_COMMAND if handler is None else handler(ctx, cmd, arrival_us)
        except (ValueError, TypeError, OverflowError, ConfigError) as exc:
            log.info("command %r rejected: %s", cmd, exc)
            reason = why.BAD_ARGUMENT
        except Exception as exc:  # a bad command never stops the board
            log.warning("command %r failed: %s", cmd, exc)
            reason = why.INTERNAL_ERROR
        ok = reason == why.NONE
        if not ok:
            ctx.counters.nacks += 1
            ctx.counters.rx_errors += 1  # a refused command shows in the next STATUS
        return protocols.Ack(token=cmd.token, opcode=cmd.opcode, ok=ok, reason=reason)

    def on_command(self, ctx: TickContext) -> None:
        """Poll the link, execute what the budget admits, answer or refuse the rest."""
        link = ctx.link
        assert link is not None
        if link is not self._link or self._budget is None:
            self._link, self._budget = link, CommandBudget(ctx.config.tick_s,
                                                           link.answer_wire_s)
        t_end_us = ctx.board_time_us()
        pending = self._pending
        room = PENDING_COMMANDS - len(pending)
        commands, excess = link.poll_commands(room)  # the rest are refused: no record built
        ctx.counters.rx_errors += link.take_rx_errors()
        budget = self._budget
        budget.new_tick()
        self._statuses_owed = 0
        pending.extend((cmd, t_end_us) for cmd in commands)  # a burst waits, its arrival kept
        if excess.shape[0]:  # no room in the queue
            self._refuse_excess(ctx, excess)
        while pending:  # in arrival order: a QUERY_STATUS needs no budget, the others do
            cmd, arrival_us = pending[0]
            if _is_query(cmd):
                self._answer_query(ctx, cmd)
            elif budget.admit():
                self._execute(ctx, cmd, arrival_us)
            else:
                break
            pending.popleft()
        if self._statuses_owed > 1:  # one more STATUS answers the later QUERY_STATUS
            ctx.queue_status()

    def _execute(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> None:
        """Execute a host command and queue its ACK (a QUERY_SESSION's SESSION after it)."""
        ctx.queue_record(self.handle(ctx, cmd, arrival_us))
        if (not isinstance(cmd, protocols.Decision)
                and cmd.opcode == protocols.CommandCode.QUERY_SESSION):
            ctx.queue_session(protocols.SessionReason.REQUEST)

    def _refuse_busy(self, ctx: TickContext, keys: list[tuple[int, int]], n: int) -> None:
        """``n`` commands beyond the tick's budget, the first of them (token, opcode)
        ``keys``: not executed, counted (``busy``, ``nacks``, ``rx_errors``); NACKed BUSY in
        order while the answer bucket has room."""
        c = ctx.counters
        c.commands += n
        c.busy += n
        c.nacks += n
        c.rx_errors += n
        assert self._budget is not None
        for token, opcode in keys:
            if not self._budget.answer_busy():
                return
            ctx.queue_record(protocols.Ack(token=token, opcode=opcode, ok=False,
                                           reason=protocols.NackReason.BUSY))

    def _answer_query(self, ctx: TickContext, cmd: Any) -> None:
        """Execute and ACK a QUERY_STATUS (never refused): the tick's first is followed by a
        STATUS at once, any later one by a STATUS at the end of the tick (two at most)."""
        assert self._budget is not None
        self._budget.admit_query()
        ctx.queue_record(self.handle(ctx, cmd))
        self._statuses_owed += 1
        if self._statuses_owed == 1:
            ctx.queue_status()

    def _refuse_excess(self, ctx: TickContext, excess: np.ndarray) -> None:
        """The commands the link did not build into records (the pending queue had no room for
        them): each QUERY_STATUS answered, the others refused BUSY."""
        query = excess["opcode"] == _QUERY_STATUS
        for token in excess["token"][query].tolist():
            self._answer_query(ctx, protocols.Command(token, protocols.CommandCode.QUERY_STATUS))
        rest = excess[~query]
        if rest.shape[0]:
            by_opcode = ctx.counters.busy_by_opcode
            opcodes, counts = np.unique(rest["opcode"], return_counts=True)
            for opcode, n in zip(opcodes.tolist(), counts.tolist(), strict=True):
                by_opcode[opcode] = by_opcode.get(opcode, 0) + n
            self._refuse_busy(ctx, rest[:int(ANSWER_BURST)].tolist(), rest.shape[0])
