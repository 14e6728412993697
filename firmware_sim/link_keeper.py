"""The board's link: opened at start, its use accounted, and when it goes away either the
run stops with :class:`skinhil.errors.TransportError` or, with ``reconnect``, the clock
keeps running (events dropped as ``link_down``) and the link is reopened every
``reconnect_period_s``."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

import protocols
from firmware_sim.link import BoardLink
from firmware_sim.tick import Participant, TickContext
from skinhil.errors import TransportError
from skinhil.transports import Transport

log = logging.getLogger(__name__)


class LinkKeeper(Participant):
    """Opens links with ``open_link()`` (a :class:`~skinhil.transports.Transport`, or
    :class:`TransportError`) for a board of ``n_channels``; says what happens to the link
    with ``on_link(message)``."""

    def __init__(self, open_link: Callable[[], Transport[Any]], n_channels: int,
                 on_link: Callable[[str], None]) -> None:
        self._open_link = open_link
        self.n_channels = n_channels
        self.on_link = on_link
        self.losses = 0
        """Times the link went away."""
        self._next_try = 0.0
        self._wire_busy_s = 0.0
        self._units_sent = 0

    def open(self, ctx: TickContext) -> None:
        """Open the first link (raises :class:`TransportError`)."""
        ctx.link = self._make_link(ctx, self._open_link())

    def _make_link(self, ctx: TickContext, transport: Transport[Any]) -> BoardLink:
        cfg = ctx.config
        return BoardLink(transport, cfg.board_id,
                         allowance_s=cfg.tick_s, step_us=ctx.dt_us, n_channels=self.n_channels)

    def warm_up(self, ctx: TickContext) -> None:
        if ctx.link is not None:
            ctx.link.warm_up(ctx.status())

    def link(self, ctx: TickContext) -> None:
        """Serve the tick if the link is up; else try to reopen it, once a period."""
        ctx.serving = ctx.link is not None
        if ctx.serving:
            return
        now = time.monotonic()
        if now < self._next_try:
            return
        self._next_try = now + ctx.config.reconnect_period_s
        try:
            transport = self._open_link()
        except TransportError as exc:
            log.debug("reconnect: %s", exc)
            return
        ctx.link = self._make_link(ctx, transport)
        ctx.queue_session(protocols.SessionReason.RECONNECT)
        self.on_link(f"link back: {transport.name}")

    def link_lost(self, ctx: TickContext, exc: Exception) -> None:
        """The link went away with ``exc``: closed, and reopened later with ``reconnect``,
        else :class:`TransportError`."""
        self.losses += 1
        self.close(ctx)
        cfg = ctx.config
        if not cfg.reconnect:
            raise TransportError(f"{exc}; start again, or use --reconnect to wait for the "
                                 "link to return") from None
        self.on_link(f"link lost ({exc}); reconnecting every {cfg.reconnect_period_s:g} s")
        self._next_try = time.monotonic() + cfg.reconnect_period_s

    def close(self, ctx: TickContext) -> None:
        """Shut the link down, its use added to the totals."""
        if ctx.link is not None:
            self._wire_busy_s += ctx.link.pacer.busy_s
            self._units_sent += ctx.link.units_sent
            ctx.link.shutdown()
        ctx.link = None

    def units_sent(self, ctx: TickContext) -> int:
        """Bytes (serial) or frames (CAN) handed to every link so far."""
        return self._units_sent + (ctx.link.units_sent if ctx.link else 0)

    def wire_busy_s(self, ctx: TickContext) -> float:
        """Wire time (s) used on every link so far."""
        return self._wire_busy_s + (ctx.link.pacer.busy_s if ctx.link else 0.0)
