"""The board's parameters (:class:`BoardConfig`) and what a run did (:class:`BoardSummary`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from numbers import Integral, Real
from typing import Any, ClassVar

import protocols
from protocols.session_layout import MAX_SUITE_NAME_BYTES
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.neurons import MAX_SNR_DB, MIN_SNR_DB, NoiseParams, check_threads
from skinhil.model.skin import AMPLITUDES, DEFAULT_AMPLITUDE, SkinParams
from skinhil.model.timeline import Timeline
from skinhil.validation import (
    Constraints,
    InstanceOf,
    Interval,
    Options,
    Predicate,
    StrOptions,
    non_negative,
    positive,
    validate_params,
)

_WIRE_NAME = Predicate(
    lambda v: isinstance(v, str) and len(v.encode("utf-8")) <= MAX_SUITE_NAME_BYTES,
    f"a text of at most {MAX_SUITE_NAME_BYTES} UTF-8 bytes")
"""A suite's or a case's name as the SUITE record carries it (SPEC.md §3.7)."""

REALTIME_SPIN_S = 3e-4
"""Spin before each tick under ``serve --realtime`` (s): a wake-up from sleep delayed by the
hypervisor now and then makes a tick late; polling the clock for the last part of each wait
keeps the ticks on time for a share of one core (``python benchmarks/bench_serve.py
--realtime`` measures the missed ticks, the lateness and the CPU with and without it)."""
DEFAULT_RESPONSE_WINDOW_S = 0.5
"""Default response window (s) of the board's scoreboard (``serve --response-window``)."""


@dataclass(frozen=True)
class BoardConfig:
    """Board parameters (times in s, rates in events or bits per s)."""

    dt_s: float = 1e-4
    """Simulation step (s); also the timestamp resolution."""
    tick_s: float = 1e-3
    """Publish tick (s): a whole number of steps."""
    fifo_events: int = 16384
    """Event FIFO capacity (events)."""
    status_period_s: float = 0.1
    """Status/heartbeat period (s)."""
    spin_s: float = 0.0
    """The last part (s) of each wait for a tick spent polling the clock, not asleep
    (:class:`firmware_sim.clock.TickClock`); ``serve --realtime`` uses
    :data:`REALTIME_SPIN_S`."""
    tx_target_s: float = 2e-3
    """Encoded data kept ready in the transmit queue (s of wire time)."""
    snr_db: float = math.inf
    """Neuron noise SNR (dB; inf: none)."""
    noise: NoiseParams = field(default_factory=NoiseParams)
    """How the SNR becomes neuron noise (the SET_SNR command changes only the level)."""
    seed: int = 0
    """Seed of the noise and of the default random schedule."""
    board_id: int = 0
    """Board id on a CAN bus (in the arbitration ids)."""
    mechanics: str = "auto"
    """The skin's mechanics: "auto" (geometric up to 10x10, linear above), "linear" or
    "geometric" (:class:`skinhil.model.skin.SkinParams`)."""
    readout: str = "length"
    """What each spring reports: "length" (its length change) or "axial"."""
    amplitude: str = DEFAULT_AMPLITUDE
    """The skin's regime: "small" (the default) or "paper" (the paper's: M, K and C x0.01;
    :data:`skinhil.model.skin.AMPLITUDES`)."""
    size: MeshSize = PAPER_SIZE
    """The skin's top layer (rows, cols) of masses; 6x6 is the paper's 338-channel skin."""
    threads: int = 1
    """Threads the model runs on. 1: mechanics then neurons, each tick. N > 1: the mechanics
    on the board's thread and the neurons on N − 1 others, two ticks behind
    (:class:`skinhil.model.pipeline.SensorPipeline`); pays off from a few thousand channels, where
    one core cannot keep real time."""
    schedule_mode: int = Timeline.SCHEDULE_RANDOM
    """0: host-driven only, 1: default random schedule, 2: schedule file."""
    rest_s: float = 0.25
    """Rest (s) after each stimulus of the default random schedule."""
    start_running: bool = True
    """Stream from the start (False: wait for a START command)."""
    reconnect: bool = False
    reconnect_period_s: float = 0.5
    drain_timeout_s: float = 5.0
    """At the end, how long (s) the FIFO may take to drain onto the wire."""
    response_window_s: float = DEFAULT_RESPONSE_WINDOW_S
    """How long (s) after a stimulus onset a DECISION may arrive and still answer it."""
    tasks: tuple[str, ...] | None = None
    """The contact tasks the board poses, by name (a suite case's: only those whose value
    varies in it); None: every task the scene's trials allow."""
    suite_name: str = ""
    """The suite whose case the board plays, announced in its SUITE record (SPEC.md §3.7; a
    name of at most 32 UTF-8 bytes, e.g. ``tactile``); empty: no suite. The command line
    hands it over: the board never knows suites."""
    suite_version: int = 0
    """The suite's version (0..65535; 0 without a suite)."""
    suite_case: str = ""
    """The case of the suite the board plays (e.g. ``force``); empty exactly without a suite."""
    task_terms: tuple[protocols.TaskEntry, ...] = ()
    """The terms of each task the case poses (tolerance with its unit, classes), announced
    as TASK records after the SUITE (at most 255)."""
    markers: bool = True
    """Send the ground-truth MARKERs on the link. False: the **blind link** (SPEC.md §3.4):
    no byte of truth reaches the decoder; the markers go to :attr:`Board.truth_markers`
    only (``serve --score`` without ``--markers``)."""

    @property
    def steps_per_tick(self) -> int:
        return int(round(self.tick_s / self.dt_s))

    _parameter_constraints: ClassVar[Constraints] = {
        "dt_s": positive("s", "the simulation step, e.g. 1e-4"),
        "tick_s": positive("s", "the publish tick, e.g. 1e-3"),
        "fifo_events": Interval(Integral, 1, None, closed="left", unit="events"),
        "status_period_s": positive("s"),
        "spin_s": non_negative("s"),
        "tx_target_s": positive("s"),
        "snr_db": [Interval(Real, MIN_SNR_DB, MAX_SNR_DB, closed="both", unit="dB"),
                   Options([math.inf])],
        "noise": InstanceOf(NoiseParams),
        "seed": Interval(Integral, 0, None, closed="left"),
        "board_id": Interval(Integral, 0, None, closed="left"),
        "mechanics": SkinParams._parameter_constraints["mechanics"],
        "readout": SkinParams._parameter_constraints["readout"],
        "amplitude": StrOptions(set(AMPLITUDES)),
        "threads": Interval(Integral, 1, None, closed="left", unit="threads"),
        "schedule_mode": Options([Timeline.SCHEDULE_NONE, Timeline.SCHEDULE_RANDOM,
                                  Timeline.SCHEDULE_FILE]),
        "rest_s": non_negative("s"),
        "reconnect_period_s": positive("s"),
        "drain_timeout_s": non_negative("s"),
        "response_window_s": positive("s", "the response window (--response-window), e.g. 0.5"),
        "suite_name": _WIRE_NAME,
        "suite_version": Interval(Integral, 0, 0xFFFF, closed="both"),
        "suite_case": _WIRE_NAME,
        "task_terms": Predicate(
            lambda v: isinstance(v, tuple) and len(v) <= 0xFF
            and all(isinstance(t, protocols.TaskEntry) for t in v),
            "a tuple of at most 255 protocols.TaskEntry"),
    }

    def check(self) -> BoardConfig:
        """Return self if consistent, else raise :class:`ConfigError`: each field as
        declared, then the rules that tie them together."""
        validate_params(self, where="board: ")
        us = self.dt_s * 1e6
        if abs(us - round(us)) > 1e-6 or round(us) < 1:
            raise ConfigError(f"step {self.dt_s!r} s is not a whole number of microseconds")
        n = self.tick_s / self.dt_s
        if not (math.isfinite(n) and n >= 1 and abs(n - round(n)) < 1e-6):
            raise ConfigError(f"tick {self.tick_s!r} s must be a whole number (>= 1) of "
                              f"steps of {self.dt_s!r} s")
        if not self.spin_s < self.tick_s:
            raise ConfigError(f"spin {self.spin_s!r} s must lie in [0, tick {self.tick_s!r} s)")
        check_threads(self.threads)
        if (not self.suite_name) != (not self.suite_case) or (
                not self.suite_name and (self.suite_version or self.task_terms)):
            raise ConfigError(f"board: suite {self.suite_name!r} case {self.suite_case!r} "
                              f"version {self.suite_version}: give a suite name, case and "
                              "version (and the tasks' terms), or none of them")
        return self


@dataclass(frozen=True)
class BoardSummary:
    """What a run did: counters, timing and link use."""

    board_time_s: float
    wall_s: float
    cpu_s: float
    generated: int
    sent: int
    dropped: int
    dropped_by: dict[str, int]
    queued: int
    ticks: int
    deadline_misses: int
    lateness_ms: dict[str, float]
    commands: int
    nacks: int
    rx_errors: int
    link_losses: int
    markers_sent: int
    markers_dropped: int
    """Ground-truth markers not sent: the board was stopped or the link was gone when they
    fell due (see :mod:`firmware_sim.counters`)."""
    units_sent: int
    """Bytes (serial) or frames (CAN) handed to the link."""
    wire_busy_s: float
    """Wire time (s) used."""
    busy: int = 0
    """Host commands refused BUSY, beyond the tick's budget
    (:mod:`firmware_sim.command_budget`)."""
    scoreboard: dict[str, Any] = field(default_factory=dict)
    """The decoder under test's scoreboard (:meth:`DecisionScoreboard.summary`)."""
    tasks: dict[str, Any] = field(default_factory=dict)
    """Its ANSWERs' scores per task (:meth:`TaskScoreboard.summary`)."""

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)
