"""The model's participants, one of which a board holds: the skin and its neurons on the
board's thread (:class:`SingleThreadModel`), the two stages on threads of their own
(:class:`PipelineModel`), or the skin touching a scene's contacts (:class:`TouchModel`).

Each steps the model one tick in the ``model`` phase (``ctx.spikes`` from step
``ctx.first``), executes SET_SNR, and in ``warm_up`` runs its compiled code once off the
clock and goes back to rest with its noise streams where they were: the board then plays
exactly what the same seed gives offline (:func:`skinhil.receiver.training.board_stream`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import protocols
from firmware_sim.tick import CommandHandler, Participant, TickContext
from skinhil.model.neurons import MAX_SNR_DB, MIN_SNR_DB
from skinhil.model.pipeline import SensorPipeline
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import Schedule, ScheduledStimulus
from skinhil.model.timeline import Timeline
from skinhil.world import TouchSensor, TruthLog


class SingleThreadModel(Participant):
    """Mechanics then neurons on the board's thread, the schedule's forces made inside the
    compiled step."""

    def __init__(self, sensor: SkinSensor, timeline: Timeline) -> None:
        self.sensor = sensor
        self.timeline = timeline

    def _stepper(self) -> Any:
        """What steps the neurons and takes SET_SNR."""
        return self.sensor

    def _sync(self, ctx: TickContext) -> None:
        ctx.step_index = ctx.spike_index = self.sensor.step_index

    def _schedule(self, ctx: TickContext, first: int) -> Schedule:
        dt = ctx.config.dt_s
        return self.timeline.schedule_for(first * dt, (first + ctx.config.steps_per_tick - 1) * dt)

    def model(self, ctx: TickContext) -> None:
        first = self.sensor.step_index
        _, ctx.spikes = self.sensor.advance_schedule(self._schedule(ctx, first),
                                                     ctx.config.steps_per_tick)
        ctx.first = first
        self._sync(ctx)

    def flush(self, ctx: TickContext) -> None:
        ctx.spikes = None  # nothing in flight

    def commands(self) -> dict[int, CommandHandler]:
        return {protocols.CommandCode.SET_SNR: self._set_snr}

    def _set_snr(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
        snr = float(cmd.arg)
        if not (snr == math.inf or MIN_SNR_DB <= snr <= MAX_SNR_DB):
            return protocols.NackReason.BAD_ARGUMENT  # documented range: SPEC.md §3.6
        self._stepper().set_snr(snr)
        ctx.snr_db = snr
        return protocols.NackReason.NONE

    def _warm_steps(self, ctx: TickContext, t_s: np.ndarray) -> None:
        n = ctx.config.steps_per_tick
        self.sensor.advance_schedule(self.timeline.schedule_for(t_s[0], t_s[-1]), n)

    def warm_up(self, ctx: TickContext) -> None:
        streams = self.sensor.neurons.noise_streams()
        n = ctx.config.steps_per_tick
        t_s = np.arange(n) * ctx.config.dt_s
        self._warm_steps(ctx, t_s)
        for entry in self.timeline.schedule.entries[:1]:  # a stimulus while it is active
            Schedule((ScheduledStimulus(0.0, entry.stimulus, 0),)).force_at(
                t_s, entry.stimulus.size)
        self.sensor.events(np.zeros((n, self.sensor.model.n_springs), dtype=bool), 0)
        self._stepper().reset()  # a pipeline waits for its threads
        self.sensor.neurons.restore_noise_streams(streams)
        self._rest(ctx)
        self._sync(ctx)

    def _rest(self, ctx: TickContext) -> None:
        """After the warm-up's reset: anything else back to its start."""


class PipelineModel(SingleThreadModel):
    """The mechanics on the board's thread, the neurons on threads of their own two ticks
    behind (:class:`skinhil.model.pipeline.SensorPipeline`): a tick publishes the spikes of
    two ticks before."""

    def __init__(self, sensor: SkinSensor, timeline: Timeline) -> None:
        super().__init__(sensor, timeline)
        self.pipeline = SensorPipeline(sensor)

    def _stepper(self) -> Any:
        return self.pipeline

    def _sync(self, ctx: TickContext) -> None:
        ctx.step_index = self.sensor.step_index
        ctx.spike_index = self.pipeline.spike_index

    def model(self, ctx: TickContext) -> None:
        first = self.sensor.step_index
        ctx.spikes, ctx.first = self.pipeline.advance(self.timeline.forces(
            (first + np.arange(ctx.config.steps_per_tick)) * ctx.config.dt_s))
        self._sync(ctx)

    def flush(self, ctx: TickContext) -> None:
        ctx.spikes = None
        if self.pipeline.in_flight:
            ctx.spikes, ctx.first = self.pipeline.flush()  # the last two ticks' spikes
            self._sync(ctx)

    def _warm_steps(self, ctx: TickContext, t_s: np.ndarray) -> None:
        for _ in range(2):  # the second call starts the neurons on the first block
            self.pipeline.advance(self.timeline.forces(t_s))


class TouchModel(SingleThreadModel):
    """The skin touching the scene's contacts inside the compiled step; the contacts' truth
    of every tick kept in ``truth`` and handed on as ``ctx.raw``."""

    def __init__(self, touch: TouchSensor, timeline: Timeline, truth: TruthLog) -> None:
        super().__init__(touch.sensor, timeline)
        self.touch = touch
        self.truth = truth

    def model(self, ctx: TickContext) -> None:
        first = self.sensor.step_index
        _, ctx.spikes, ctx.raw = self.touch.advance_schedule(self._schedule(ctx, first),
                                                             ctx.config.steps_per_tick)
        ctx.first = first
        self.truth.add_raw(first * ctx.dt_us, ctx.raw[0])
        self._sync(ctx)

    def _warm_steps(self, ctx: TickContext, t_s: np.ndarray) -> None:
        self.touch.start(0.0)  # the contact kernel compiled or loaded
        self.touch.advance_schedule(self.timeline.schedule_for(t_s[0], t_s[-1]),
                                    ctx.config.steps_per_tick)

    def _rest(self, ctx: TickContext) -> None:
        self.truth.clear()
        ctx.start_scene(self.timeline.mode, 0.0)


def model_for(sensor: SkinSensor, timeline: Timeline, touch: TouchSensor | None,
              truth: TruthLog, threads: int) -> SingleThreadModel:
    """The model participant: touching the scene with one, else on ``threads`` threads."""
    if touch is not None:
        return TouchModel(touch, timeline, truth)
    return PipelineModel(sensor, timeline) if threads > 1 else SingleThreadModel(sensor, timeline)
