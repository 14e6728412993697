"""The encoder and its pacing: the model's events into the event FIFO (or dropped by
reason, :mod:`firmware_sim.counters`), then encoded in filled frames into the link's
transmit queue while it holds less than ``tx_target_s`` of wire time, each ground-truth
marker after every event before its time; the queue onto the wire within its budget
(:class:`firmware_sim.link.BoardLink`)."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

import numpy as np

import protocols
from firmware_sim.tick import Participant, TickContext
from skinhil.errors import TransportError
from skinhil.model.timeline import MarkerEvent

log = logging.getLogger(__name__)


class Encoder(Participant):
    """The events of ``events_of(spikes, first)`` and the markers on their way to the wire."""

    def __init__(self, events_of: Callable[[np.ndarray, int], np.ndarray]) -> None:
        self.events_of = events_of
        self._markers: list[MarkerEvent] = []
        """Markers due and not yet queued: each waits for the events before its time."""

    def attach(self, ctx: TickContext) -> None:
        ctx.fill = lambda: self.fill(ctx)

    def publish(self, ctx: TickContext) -> None:
        """This tick's events counted as generated and pushed into the FIFO (or dropped),
        its markers kept for the wire (or dropped)."""
        assert ctx.spikes is not None
        events = self.events_of(ctx.spikes, ctx.first)
        c = ctx.counters
        c.generated += len(events)
        if ctx.link is None:
            c.drop("link_down", len(events))
        elif not ctx.running:
            c.drop("stopped", len(events))
        else:
            c.drop("fifo_full", ctx.fifo.push(events))
        if ctx.link is None or not ctx.running:
            self._drop_markers(ctx, ctx.markers)
        elif ctx.config.markers:
            self._markers.extend(ctx.markers)

    def encode(self, ctx: TickContext) -> None:
        self.fill(ctx)

    def send(self, ctx: TickContext) -> None:
        assert ctx.link is not None
        ctx.link.pump()

    def link_lost(self, ctx: TickContext, exc: Exception) -> None:
        ctx.counters.drop("link_down", ctx.fifo.clear())
        self._drop_markers(ctx, self._markers)

    def fill(self, ctx: TickContext) -> None:
        """Encode the FIFO's events in filled frames, and the due markers, while the
        transmit queue holds less than ``tx_target_s`` of wire time.

        Everything queued goes when it fits: the last frame closes after the last event
        generated (the flush, every tick). When the FIFO holds more than the queue has room
        for, the encoder writes only whole frames, as many as the room takes (rounded up:
        the queue may pass its target by less than one frame), and the events left wait for
        the next call, so a backlog leaves in full frames. A marker is queued once every
        event before its time is, so it may follow its events by up to one batch.
        """
        link, fifo = ctx.link, ctx.fifo
        assert link is not None
        t_end_us = ctx.board_time_us()
        target = ctx.config.tx_target_s
        while True:
            head = fifo.peek_time_us()
            self._send_markers(ctx, head)
            if head is None:
                if ctx.running:  # an empty call: keeps the time base alive (SYNC)
                    link.queue_events(fifo.pop(0), t_end_us)
                return
            room = target - link.backlog_s()
            if room <= 0:
                return
            frames = max(1, math.ceil(room / link.frame_s))
            n = len(fifo)
            if n > frames * link.frame_events:  # a batch never splits a step
                n = fifo.count_before(fifo.time_at(frames * link.frame_events - 1)
                                      + ctx.dt_us)
            batch = fifo.peek(n)
            end = t_end_us if n == len(fifo) else fifo.time_at(n)
            used = link.queue_events(batch, end, frames)
            fifo.pop(used)
            ctx.counters.sent += used

    def finish(self, ctx: TickContext) -> None:
        """Drain the FIFO for at most ``drain_timeout_s``, count what is left as dropped at
        ``shutdown``, queue the markers still due, a final status and the RUN_END record
        saying ``ctx.end_reason``, and send the whole transmit queue (it holds at most
        ``tx_target_s`` and one frame more, plus these records: events counted as sent
        always reach the wire)."""
        link = ctx.link
        if link is None:
            return
        end = time.monotonic() + ctx.config.drain_timeout_s
        try:
            while (len(ctx.fifo) or self._markers) and time.monotonic() < end:
                self.fill(ctx)
                link.pump()
                time.sleep(ctx.config.tick_s / 4)
            ctx.counters.drop("shutdown", ctx.fifo.clear())
            self._send_markers(ctx, None)  # ground truth is never left behind with events
            link.queue_record(ctx.status())
            link.queue_record(protocols.RunEnd(t_us=ctx.board_time_us(), reason=ctx.end_reason))
            link.drain(max(0.5, end - time.monotonic(), 2 * link.backlog_s() + 0.5))
            link.wait_wire_idle(1.0)
        except TransportError as exc:
            log.warning("link lost while finishing: %s", exc)
            self._drop_markers(ctx, self._markers)

    def _send_markers(self, ctx: TickContext, before_us: int | None) -> None:
        """Queue the due ground-truth markers with ``t_us <= before_us`` (all if None): every
        event before a marker's time is on the wire ahead of it."""
        while self._markers and (before_us is None or self._markers[0].t_us <= before_us):
            m = self._markers.pop(0)
            phase = (protocols.MarkerPhase.ONSET if m.phase == "onset"
                     else protocols.MarkerPhase.END)
            ctx.queue_record(protocols.Marker(t_us=m.t_us, stimulus_id=m.stimulus_id,
                                              phase=phase))
            ctx.counters.markers_sent += 1

    @staticmethod
    def _drop_markers(ctx: TickContext, markers: list[MarkerEvent]) -> None:
        """``markers`` will never be sent (board stopped, link gone): count them, forget them."""
        ctx.counters.markers_dropped += len(markers)
        markers.clear()
