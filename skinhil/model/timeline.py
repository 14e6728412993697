"""What the board's skin feels, on the board's clock: schedules, host stimuli, markers.

Everything here is in board time (s since the board started). Three sources of stimuli:

- the default schedule: a seeded random sequence of the 9 direction conditions
  (:func:`skinhil.direction_conditions`, ids 0..8) with ``rest_s`` of rest after each,
  extended block by block so it never runs out;
- a schedule from a TOML file (:func:`skinhil.load_schedule`), played once;
- host commands: a stimulus started now (SET_STIMULUS), or a schedule (re)started now.

Each stimulus yields two ground-truth markers: ``onset`` at its onset and ``end`` when its
indentation phase ends, at the step where they fall (µs, multiples of the step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.stimuli import (
    Schedule,
    ScheduledStimulus,
    Stimulus,
    at_size,
    check_total_force,
    direction_conditions,
    random_schedule,
)
from skinhil.model.stimulus_table import catalog

DEFAULT_REST_S = 0.25
"""Rest (s) after each stimulus of the default random schedule."""
_BLOCK = 64
"""Stimuli added to the default schedule at a time (about 55 s of board time)."""
EXTEND_AHEAD_S = 10.0
""":meth:`Timeline.prepare` extends the default schedule when less than this (s) is left."""
_EXTEND_LATE_S = 2.0
""":meth:`Timeline.forces` extends it itself (on the tick) only when less than this is left."""


@dataclass(frozen=True)
class MarkerEvent:
    """A ground-truth marker: stimulus ``stimulus_id`` reached ``phase`` at ``t_us`` (µs)."""

    t_us: int
    stimulus_id: int
    phase: str
    """"onset" or "end"."""


class Timeline:
    """Stimuli in board time, the force they apply, and the markers they announce.

    ``dt_s`` is the simulation step (s): marker times are rounded up to the first step at
    or after the phase change, which is where the force changes in the stepped model.
    ``size`` is the skin's top layer (rows, cols): the built-in stimuli are moved to it
    (:func:`skinhil.model.stimuli.at_size`) and a file schedule must be defined for it.
    """

    SCHEDULE_NONE = 0
    SCHEDULE_RANDOM = 1
    SCHEDULE_FILE = 2

    def __init__(self, dt_s: float, file_schedule: Schedule | None = None, seed: int = 0,
                 rest_s: float = DEFAULT_REST_S, mode: int = SCHEDULE_RANDOM,
                 size: MeshSize = PAPER_SIZE) -> None:
        self.dt_s = float(dt_s)
        self.file_schedule = file_schedule
        self.seed = int(seed)
        self.rest_s = float(rest_s)
        self.size = size
        if file_schedule is not None:
            file_schedule.check_size(size)
        self.catalog: dict[int, Stimulus] = catalog(size, file_schedule)
        self._conditions = [at_size(s, size) for s in direction_conditions()]
        self._entries: list[ScheduledStimulus] = []
        self._schedule = Schedule(())
        self._random_block = 0
        self._random_end_s = math.inf
        self._pending: list[tuple[MarkerEvent, ScheduledStimulus]] = []
        self.mode = self.SCHEDULE_NONE
        self.start_schedule(mode, 0.0)

    @property
    def schedule(self) -> Schedule:
        """The stimuli not yet finished (and those started), in board time (s).

        Stimuli that ended before the last :meth:`prepare` are forgotten, so a board that
        runs for days keeps a short schedule and a constant cost per tick.
        """
        return self._schedule

    def _add(self, entries: list[ScheduledStimulus]) -> None:
        self._entries.extend(entries)
        self._schedule = Schedule(tuple(self._entries))
        for e in entries:
            for t_s, phase in ((e.onset_s, "onset"), (e.end_s, "end")):
                t_us = int(math.ceil(t_s / self.dt_s - 1e-9)) * int(round(self.dt_s * 1e6))
                self._pending.append((MarkerEvent(t_us, e.stimulus_id, phase), e))
        self._pending.sort(key=lambda m: (m[0].t_us, m[0].phase != "end"))

    def _clear_future(self, now_s: float) -> None:
        """Drop stimuli that have not started by ``now_s`` (and their markers)."""
        keep = [e for e in self._entries if e.onset_s < now_s]
        self._entries = keep
        self._schedule = Schedule(tuple(keep))
        self._pending = [(m, e) for m, e in self._pending if e.onset_s < now_s]

    def start_schedule(self, mode: int, now_s: float) -> bool:
        """Replace future stimuli by schedule ``mode`` starting at ``now_s`` (s).

        ``mode``: 0 none (host-driven), 1 the default random schedule, 2 the schedule file.
        Returns False (and changes nothing) for an unknown mode or a missing file schedule.
        """
        if mode not in (self.SCHEDULE_NONE, self.SCHEDULE_RANDOM, self.SCHEDULE_FILE):
            return False
        if mode == self.SCHEDULE_FILE and self.file_schedule is None:
            return False
        self._clear_future(now_s)
        self.mode = mode
        self._random_end_s = math.inf
        if mode == self.SCHEDULE_RANDOM:
            self._random_end_s = now_s
            self._random_block = 0
            self._extend_random()
        elif mode == self.SCHEDULE_FILE:
            assert self.file_schedule is not None
            self._add([ScheduledStimulus(now_s + e.start_s, e.stimulus, e.stimulus_id)
                       for e in self.file_schedule.entries])
        return True

    def _extend_random(self) -> None:
        block = random_schedule(self._conditions, _BLOCK, self.rest_s,
                                seed=self.seed + self._random_block,
                                lead_s=0.1 if self._random_block == 0 else 0.0)
        t0 = self._random_end_s
        entries = [ScheduledStimulus(t0 + e.start_s, e.stimulus, e.stimulus_id)
                   for e in block.entries]
        self._random_block += 1
        last = entries[-1]
        self._random_end_s = last.end_s + self.rest_s
        self._add(entries)

    def start_stimulus(self, stimulus_id: int, now_s: float) -> bool:
        """Start stimulus ``stimulus_id`` at ``now_s`` (s); False if the id is unknown.
        Raises :class:`ConfigError` if it would press a mass harder than
        :data:`~skinhil.model.stimuli.MAX_FORCE_N` with the stimuli still pressing."""
        stim = self.catalog.get(int(stimulus_id))
        if stim is None:
            return False
        new = ScheduledStimulus(now_s, stim, int(stimulus_id))
        check_total_force([e for e in self._entries if e.end_s > now_s] + [new],
                          f"stimulus {int(stimulus_id)}")
        self._add([new])
        return True

    def prepare(self, now_s: float) -> bool:
        """Housekeeping off the tick: extend the default schedule when less than
        :data:`EXTEND_AHEAD_S` (s) of it is left after board time ``now_s`` (s), forgetting
        the stimuli that ended before ``now_s``. Returns True if it did anything.

        The board calls this in a tick's spare time, so the per-tick path (:meth:`forces`)
        never builds schedules; :meth:`forces` still extends by itself when it gets close to
        the end (callers that never call this).
        """
        if self.mode != self.SCHEDULE_RANDOM or now_s <= self._random_end_s - EXTEND_AHEAD_S:
            return False
        self._forget_before(now_s)
        self._extend_random()
        return True

    def _forget_before(self, now_s: float) -> None:
        keep = [e for e in self._entries if e.end_s >= now_s]
        if len(keep) < len(self._entries):
            self._entries = keep
            self._schedule = Schedule(tuple(keep))

    def schedule_for(self, first_s: float, last_s: float) -> Schedule:
        """The schedule that holds every stimulus of board times ``first_s`` .. ``last_s``
        (s): :attr:`schedule`, first extended when the default schedule gets close to its
        end (forgetting what ended before ``first_s``). The board's tick passes it to the
        model's compiled step (:meth:`skinhil.model.sensor.SkinSensor.advance_schedule`)."""
        if self.mode == self.SCHEDULE_RANDOM and last_s > self._random_end_s - _EXTEND_LATE_S:
            self._forget_before(first_s)
            self._extend_random()
        return self._schedule

    def forces(self, t_s: np.ndarray) -> np.ndarray:
        """External force on every mass at board times ``t_s`` (s): (len, n_masses, 3) N."""
        if t_s.size:
            self.schedule_for(float(t_s[0]), float(t_s[-1]))
        return self._schedule.force_at(t_s, self.size)

    def markers_before(self, t_end_us: int) -> list[MarkerEvent]:
        """Remove and return the markers with ``t_us < t_end_us``, in time order."""
        n = 0
        while n < len(self._pending) and self._pending[n][0].t_us < t_end_us:
            n += 1
        out, self._pending = self._pending[:n], self._pending[n:]
        return [m for m, _ in out]
