"""The board's tick as data: the phases in order (:data:`SCHEDULE`), the participant that
takes part in them (:class:`Participant`) and the context each hook is handed
(:class:`TickContext`).

A participant owns its state and reaches the rest of the board only through the context:
board time, the outbound record queue, the counters, the running flag, and the few services
other participants register on it (the status record, the session records, the encoder's
flush, the scene's start). A hook is a method named after its phase; a participant without
that method takes no part in the phase. Within a phase, hooks run in the order of the
board's participants (:func:`firmware_sim.participants.participants`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from firmware_sim.clock import TickClock
from firmware_sim.config import BoardConfig
from firmware_sim.counters import BoardCounters
from firmware_sim.fifo import EventFifo
from firmware_sim.link import BoardLink
from skinhil.model.timeline import MarkerEvent


@dataclass(frozen=True)
class Phase:
    """One step of the tick: the hook name and when it runs: ``always``; ``served`` (the
    link was up when the tick reached the ``link`` phase); ``wire`` (served, and the link is
    still up)."""

    name: str
    when: str = "always"

    def runs(self, serving: bool, link_up: bool) -> bool:
        """Whether the phase runs in a tick ``serving`` whose link is up (``link_up``)."""
        return self.when == "always" or serving and (self.when == "served" or link_up)


SCHEDULE: tuple[Phase, ...] = (
    Phase("before_model"),  # the held object's grip applied
    Phase("model"),  # the skin and its neurons step: ctx.spikes from step ctx.first
    Phase("after_model"),  # the contacts' truth, the task trials, the held object's response
    Phase("publish"),  # the events into the FIFO, the markers due (kept or dropped)
    Phase("link"),  # the link: reopened while it is down (the tick ends there)
    Phase("on_command", "wire"),  # host commands executed and answered
    Phase("heartbeat", "wire"),  # the STATUS every status period
    Phase("encode", "wire"),  # the FIFO's events and the markers into the transmit queue
    Phase("send", "wire"),  # the transmit queue onto the wire, within its budget
    Phase("after_tick", "served"),  # onsets and trials past their response window
)
"""The tick's phases in order, written once."""

MODEL_PHASES: tuple[str, ...] = ("before_model", "model", "after_model")
"""The model's steps of one tick with what goes just before and after them (an offline
replay runs these alone, :mod:`firmware_sim.grip_replay`)."""

FINISH: tuple[str, ...] = ("flush", "publish", "finish")
"""The end of a run: the model's last spikes (``flush``) published, then each participant's
``finish`` (the FIFO drained, a final STATUS and the RUN_END record)."""

WARM_UP: tuple[str, ...] = ("warm_up",)
"""Off the clock before the first tick: every code path run once, the model back to rest."""

HOOKS: tuple[str, ...] = (*(p.name for p in SCHEDULE), *FINISH, *WARM_UP, "attach",
                          "start_scene", "link_lost", "housekeeping")
"""Every hook a participant may have: the phases', ``attach`` (once, at construction: the
services it registers on the context), ``start_scene`` (a scene starts: mode, time in s),
``link_lost`` (the link went away: the error) and ``housekeeping`` (a tick's spare time)."""


@dataclass
class TickContext:
    """What every hook is handed: the board's shared state and registered services.

    Times in µs of board time unless named otherwise.
    """

    config: BoardConfig
    counters: BoardCounters
    fifo: EventFifo
    """The event FIFO: the model's events wait in it for the encoder."""
    clock: TickClock
    running: bool
    """Whether events and markers are streamed (START / STOP)."""
    link: BoardLink | None = None
    """The link, None while it is down."""
    serving: bool = False
    """The link was up when this tick reached its ``link`` phase."""
    step_index: int = 0
    """The mechanics' next step."""
    spike_index: int = 0
    """The step after the last one whose spikes are out (behind the mechanics with a
    pipeline): board time in steps."""
    spikes: np.ndarray | None = None
    """This tick's spikes (steps, channels), None when the model gave none."""
    first: int = 0
    """The step of the first row of :attr:`spikes`."""
    raw: np.ndarray | None = None
    """This tick's contact truth (the compiled step's raw record), with contacts only."""
    markers: list[MarkerEvent] = field(default_factory=list)
    """The ground-truth markers that fell due this tick."""
    snr_db: float = 0.0
    """The neuron noise level now (dB): what SESSION records say."""
    end_reason: Any = None
    """What the RUN_END record says (set before ``finish``)."""
    status: Callable[[], Any] = lambda: None
    """The counters now as a STATUS record (registered by the status participant)."""
    queue_session: Callable[[Any], None] = lambda reason: None
    """Queue the SESSION record and the stimulus table for ``reason``."""
    fill: Callable[[], None] = lambda: None
    """Encode the FIFO's events and the due markers into the transmit queue."""
    start_scene: Callable[[int, float], None] = lambda mode, now_s: None
    """The scene plays from ``now_s`` (s) in schedule mode ``mode`` (``start_scene`` hooks)."""
    dt_us: int = field(init=False)
    """The step (µs)."""

    def __post_init__(self) -> None:
        self.dt_us = int(round(self.config.dt_s * 1e6))

    def board_time_us(self) -> int:
        """Board time (µs): the end of the last step whose spikes are out."""
        return self.spike_index * self.dt_us

    def queue_record(self, record: Any) -> None:
        """Queue ``record`` on the link (the link must be up)."""
        assert self.link is not None
        self.link.queue_record(record)

    def queue_status(self) -> None:
        """Encode the events already generated, then queue a STATUS: its counts agree with
        the stream."""
        self.fill()
        self.queue_record(self.status())


CommandHandler = Callable[[TickContext, Any, "int | None"], Any]
"""A host command's handler: (context, command, arrival µs or None) → its NACK reason
(:class:`protocols.NackReason`; NONE for an ACK)."""


class Participant:
    """A part of the board taking part in the tick through hooks named after the phases of
    :data:`SCHEDULE`, :data:`FINISH` and :data:`WARM_UP` (and ``start_scene``,
    ``link_lost``, ``housekeeping``), and in the host commands through :meth:`commands`."""

    def commands(self) -> dict[int, CommandHandler]:
        """The host commands this participant executes: opcode → handler."""
        return {}
