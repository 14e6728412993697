"""The held object a scene's lifts carry (:class:`skinhil.plant.HeldObject`): its grip
applied before the model's steps, its response and truth after them, GRIP commands."""

from __future__ import annotations

from typing import Any

import protocols
from firmware_sim.tick import CommandHandler, Participant, TickContext
from skinhil.plant import HeldObject
from skinhil.world import TouchSensor, TruthLog


class HeldObjectStage(Participant):
    """The held object ``plant`` on the skin of ``touch``, its truth into ``truth``."""

    def __init__(self, plant: HeldObject, touch: TouchSensor, truth: TruthLog) -> None:
        self.plant = plant
        self.touch = touch
        self.truth = truth

    def before_model(self, ctx: TickContext) -> None:
        self.plant.before_tick()

    def after_model(self, ctx: TickContext) -> None:
        dt, first = ctx.config.dt_s, ctx.first
        assert ctx.raw is not None
        self.truth.add_object(self.plant.after_tick(
            first * ctx.dt_us, first * dt - self.touch.scene_offset_s, dt, ctx.raw))

    def start_scene(self, ctx: TickContext, mode: int, now_s: float) -> None:
        """The grip and the lifts start again with the scene."""
        self.plant.reset()

    def commands(self) -> dict[int, CommandHandler]:
        return {protocols.CommandCode.GRIP: self._grip}

    def _grip(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
        """A GRIP executed now (the grip from the next tick on), SPEC.md §3.5.6."""
        why = protocols.NackReason
        outcome = self.plant.set_grip(float(cmd.arg), ctx.board_time_us(), arrival_us,
                                      cmd.token)
        return {"ok": why.NONE, "bad_argument": why.BAD_ARGUMENT}.get(outcome, why.GRIP_LIMIT)
