"""Replay a closed-loop session offline: the board's model stepped tick by tick, each GRIP of
the session's grip log executed at the board time it was executed live.

Live, a tick steps the model and then executes the commands read (:meth:`Board.tick`); a
GRIP holds from the next tick on. Here :meth:`Board.step_model` (the tick's model phases)
and :meth:`Board.handle` run in that same order, with no clock and no link traffic, so the
held object's truth and the contacts' (the board's :class:`~skinhil.world.TruthLog`) come
out bit for bit as they were (tests/test_grasp_loop.py).
"""

from __future__ import annotations

from collections.abc import Iterable

import protocols
from firmware_sim.board import Board
from skinhil.plant.object import GripEntry


def replay_grips(board: Board, log: Iterable[GripEntry], ticks: int) -> None:
    """Step ``board`` (a fresh board like the session's) ``ticks`` ticks from its start,
    executing each GRIP of ``log`` after the tick that ends at its ``applied_us``."""
    todo = sorted(log, key=lambda e: e.applied_us)
    board.warm_up()
    i = 0
    for _ in range(ticks):
        board.step_model()
        now = board.board_time_us()
        while i < len(todo) and todo[i].applied_us <= now:
            e = todo[i]
            board.handle(protocols.Command(e.token, protocols.CommandCode.GRIP, e.grip_n),
                         e.arrival_us)
            i += 1
