"""The decoder under test's scores: its DECISIONs against the onsets the board sent
(:class:`skinhil.scoring.DecisionScoreboard`) and its ANSWERs of the contact tasks against
the contacts' truth (:class:`skinhil.scoring.TaskScoreboard`), SPEC.md §3.5."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import protocols
from firmware_sim.tick import CommandHandler, Participant, TickContext
from skinhil.plant import HeldObject
from skinhil.scoring import DecisionScoreboard, TaskScoreboard, answer_reason
from skinhil.tasks import registry as task_registry
from skinhil.tasks import tasks_mask
from skinhil.world import Scene

log = logging.getLogger(__name__)


class Scoring(Participant):
    """The scoreboard, and the task scoreboard when a scenario's contacts pose tasks."""

    def __init__(self, scoreboard: DecisionScoreboard, tasks: TaskScoreboard | None) -> None:
        self.scoreboard = scoreboard
        self.tasks = tasks

    @classmethod
    def posed_by(cls, response_window_s: float, known: Callable[[int], bool],
                 scene: Scene | None, plant: HeldObject | None,
                 only: tuple[str, ...] | None = None) -> Scoring:
        """The scores of a board whose stimulus ids ``known`` says and whose scene poses
        the contact tasks (a held object's lifts pose the grasp task alone; ``only``: just
        the tasks it names)."""
        tasks = None
        if scene is not None and plant is None:
            tasks = TaskScoreboard(
                [c.trajectory.vibration_frequency_hz if c.trajectory.vibration_amplitude_m > 0
                 else 0.0 for c in scene.contacts], response_window_s, only=only)
        return cls(DecisionScoreboard(response_window_s, known), tasks)

    def after_model(self, ctx: TickContext) -> None:
        if self.tasks is not None and ctx.running and ctx.link is not None:
            assert ctx.raw is not None  # a scene's contacts pose the tasks
            self.tasks.observe(ctx.first * ctx.dt_us, ctx.raw[0])

    def publish(self, ctx: TickContext) -> None:
        if ctx.link is not None and ctx.running:
            for m in ctx.markers:  # the ground truth the decoder under test is scored against
                if m.phase == "onset":
                    self.scoreboard.onset(m.stimulus_id, m.t_us)

    def after_tick(self, ctx: TickContext) -> None:
        self.scoreboard.advance(ctx.board_time_us())
        if self.tasks is not None:
            self.tasks.advance(ctx.board_time_us())

    def posed_tasks(self) -> int:
        """The tasks whose ANSWERs this board scores, bit n for task n (SPEC.md §3.7):
        classification always (a DECISION's), the contact tasks a scenario poses."""
        return tasks_mask([protocols.Task.CLASSIFICATION,
                           *(self.tasks.tasks if self.tasks else ())])

    def commands(self) -> dict[int, CommandHandler]:
        codes = protocols.CommandCode
        return {codes.DECISION: self._decision, codes.ANSWER: self._answer}

    def _decision(self, ctx: TickContext, cmd: Any, arrival_us: int | None) -> Any:
        if not isinstance(cmd, protocols.Decision):
            return protocols.NackReason.UNKNOWN_COMMAND
        return self._score(ctx, cmd, ctx.board_time_us() if arrival_us is None else arrival_us)

    def _score(self, ctx: TickContext, decision: Any, t_us: int) -> Any:
        """Stamp a DECISION with its arrival's board time ``t_us`` (µs) and score it; its
        NACK reason (NONE when scored, NOT_RUNNING while stopped, UNKNOWN_STIMULUS for an id
        the board does not know: counted all the same)."""
        outcome = self.scoreboard.decision(decision.stimulus_id, t_us,
                                           decision.confidence, ctx.running, decision.token)
        log.debug("decision %r: %s", decision, outcome.value)
        return answer_reason(outcome)

    def _answer(self, ctx: TickContext, answer: Any, arrival_us: int | None) -> Any:
        """Score an ANSWER arriving at board time ``arrival_us`` (µs), SPEC.md §3.5.3: a
        CLASSIFICATION as a DECISION without confidence, the contact tasks against the truth;
        its NACK reason (UNKNOWN_TASK, TASK_NOT_POSED: counted too)."""
        if not isinstance(answer, protocols.Answer):
            return protocols.NackReason.UNKNOWN_COMMAND
        t_us = ctx.board_time_us() if arrival_us is None else arrival_us
        task = int(answer.task)
        if task == protocols.Task.CLASSIFICATION:
            return self._score(ctx, protocols.Decision(answer.token, int(answer.values[0])),
                               t_us)
        if task_registry.task(task) is None:
            return protocols.NackReason.UNKNOWN_TASK
        if self.tasks is None or not self.tasks.posed(task):
            if self.tasks is not None:
                self.tasks.not_posed[task] += 1
            return protocols.NackReason.TASK_NOT_POSED
        outcome = self.tasks.answer(answer, t_us, ctx.running)
        log.debug("answer %r: %s", answer, outcome)
        return (protocols.NackReason.NOT_RUNNING if outcome == "while_stopped"
                else protocols.NackReason.NONE)
