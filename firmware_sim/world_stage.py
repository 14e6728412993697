"""The stimulus and the world: the timeline (the schedule's stimuli and their markers) and
the scene's contacts, which play while the schedule file does (schedule mode 2)."""

from __future__ import annotations

from typing import Any

import protocols
from firmware_sim.tick import CommandHandler, Participant, TickContext
from skinhil.model.skin import SkinModel
from skinhil.model.timeline import MarkerEvent, Timeline
from skinhil.world import TouchSensor

MAX_TRUTH_MARKERS = 1_000_000
"""Markers :attr:`StimulusWorld.truth_markers` keeps (about 100 MB at most)."""


class StimulusWorld(Participant):
    """The timeline and, with a scene, the skin's contacts (``touch``)."""

    def __init__(self, timeline: Timeline, model: SkinModel,
                 touch: TouchSensor | None) -> None:
        self.timeline = timeline
        self.skin = model
        self.touch = touch
        self.truth_markers: list[MarkerEvent] = []
        """Every marker that fell due while running with the link up, sent or (on the blind
        link) withheld: the operator's truth (``serve --truth``), the first
        :data:`MAX_TRUTH_MARKERS`."""

    def publish(self, ctx: TickContext) -> None:
        """The markers due by board time into ``ctx.markers``; the operator's copy kept."""
        ctx.markers = self.timeline.markers_before(ctx.board_time_us())
        if (ctx.link is not None and ctx.running
                and len(self.truth_markers) < MAX_TRUTH_MARKERS):
            self.truth_markers.extend(ctx.markers)

    def housekeeping(self, ctx: TickContext) -> None:
        """In a tick's spare time: the schedule extended ahead of board time."""
        self.timeline.prepare(ctx.board_time_us() * 1e-6)

    def start_scene(self, ctx: TickContext, mode: int, now_s: float) -> None:
        """The contacts play from ``now_s`` (s) with the schedule file (mode 2), else none."""
        if self.touch is not None:
            if mode == Timeline.SCHEDULE_FILE:
                self.touch.start(now_s)
            else:
                self.touch.stop()

    def commands(self) -> dict[int, CommandHandler]:
        codes = protocols.CommandCode
        return {codes.SET_STIMULUS: self._set_stimulus, codes.SET_SCHEDULE: self._set_schedule}

    @staticmethod
    def _now_s(ctx: TickContext) -> float:
        """The mechanics' next step (s): where a new stimulus or schedule starts."""
        return ctx.step_index * ctx.dt_us * 1e-6

    def _set_stimulus(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
        """SET_STIMULUS: a stimulus id (0..8 direction conditions, 10..14 paper stimuli A-E,
        100.. stimuli of the schedule file)."""
        stim = self.timeline.catalog.get(int(cmd.arg))
        if stim is not None:  # a force on a fixed mass: BAD_ARGUMENT
            self.skin.check_stimulus(stim)
        if not self.timeline.start_stimulus(int(cmd.arg), self._now_s(ctx)):
            return protocols.NackReason.UNKNOWN_STIMULUS
        return protocols.NackReason.NONE

    def _set_schedule(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
        """SET_SCHEDULE: 0 none (host-driven), 1 the default random schedule, 2 the
        schedule file (its contacts with it)."""
        now_s = self._now_s(ctx)
        if not self.timeline.start_schedule(int(cmd.arg), now_s):
            return protocols.NackReason.UNKNOWN_SCHEDULE
        ctx.start_scene(int(cmd.arg), now_s)
        return protocols.NackReason.NONE
