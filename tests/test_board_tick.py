"""The board's tick as data: which participants a board holds, the order their hooks run in,
and which participant executes each host command."""

from __future__ import annotations

from typing import Any

import protocols
from firmware_sim.board import Board, BoardConfig
from firmware_sim.model_stage import PipelineModel, SingleThreadModel, TouchModel
from firmware_sim.plant_stage import HeldObjectStage
from firmware_sim.scoring_stage import Scoring
from firmware_sim.status_stage import StatusReporter
from firmware_sim.tick import SCHEDULE
from firmware_sim.world_stage import StimulusWorld
from skinhil.model.timeline import Timeline
from skinhil.plant import GraspParams, lift_scene
from skinhil.transports import SerialTransport


def _board(**kwargs: object) -> Board:
    config = kwargs.pop("config", BoardConfig(seed=1, rest_s=0.05))
    return Board(config, lambda: SerialTransport("loop://", 921600), **kwargs)  # type: ignore[arg-type]


def test_threads_and_contacts_are_participants_present_or_absent() -> None:
    plain = _board()
    assert type(plain.model) is SingleThreadModel
    assert not any(isinstance(p, HeldObjectStage) for p in plain.participants)
    piped = _board(config=BoardConfig(seed=1, threads=2))
    assert type(piped.model) is PipelineModel
    params = GraspParams()
    held = _board(config=BoardConfig(seed=1, schedule_mode=Timeline.SCHEDULE_FILE),
                  scene=lift_scene(params, 2), grasp=params)
    assert type(held.model) is TouchModel
    assert [type(p).__name__ for p in held.participants] == [
        "StimulusWorld", "TouchModel", "Scoring", "HeldObjectStage", "Encoder", "HostCommands",
        "StatusReporter", "LinkKeeper"]


def test_each_host_command_is_executed_by_the_participant_owning_its_state() -> None:
    codes = protocols.CommandCode
    table = _board().commands.table
    owner = {op: type(getattr(table[op], "__self__", None)) for op in table}
    assert owner[codes.SET_STIMULUS] is StimulusWorld and owner[codes.SET_SCHEDULE] is StimulusWorld
    assert owner[codes.SET_SNR] is SingleThreadModel
    assert owner[codes.DECISION] is Scoring and owner[codes.ANSWER] is Scoring
    assert {codes.QUERY_STATUS, codes.QUERY_SESSION, codes.PING} <= set(table)
    assert owner[codes.GRIP] is type(None)  # no held object: the NO_OBJECT fallback
    board = _board()
    ack = board.handle(protocols.Command(1, codes.GRIP, 1.0))
    assert ack.reason == protocols.NackReason.NO_OBJECT
    assert board.handle(protocols.Command(2, 99)).reason == protocols.NackReason.UNKNOWN_COMMAND
    assert board.counters.nacks == 2 and board.counters.commands == 2
    params = GraspParams()
    held = _board(config=BoardConfig(seed=1, schedule_mode=Timeline.SCHEDULE_FILE),
                  scene=lift_scene(params, 2), grasp=params)
    assert type(held.commands.table[codes.GRIP].__self__) is HeldObjectStage  # type: ignore[attr-defined]
    assert isinstance(held.status_reporter, StatusReporter)


def test_a_tick_runs_the_hooks_in_the_schedule_order() -> None:
    board = _board()
    board.warm_up()
    calls: list[str] = []

    def recorded(hook: Any, name: str) -> Any:
        def run(ctx: Any) -> None:
            calls.append(name)
            hook(ctx)
        return run

    for phase in SCHEDULE:
        hooks = board._hooks[phase.name]
        hooks[:] = [recorded(h, phase.name) for h in hooks]
    for _ in range(3):
        board.tick()
    order = [p.name for p in SCHEDULE if board._hooks[p.name]]
    per_tick = [n for n in order for _ in board._hooks[n]]
    assert calls == per_tick * 3
    assert board.board_time_us() == 3000 and board.counters.commands == 0
