"""A suite case's trials simulated offline as the board plays them, cut into samples.

The run is what ``skinhil serve --suite SUITE:CASE --seed N --snr-db S`` plays: the case's
trials of seed ``N`` (:meth:`skinhil.suites.Case.generate`), the default skin, a
:class:`~skinhil.model.sensor.SkinSensor` whose neurons' noise is seeded with ``N``, the
scene's contacts touching from board time 0, the schedule played once
(:class:`~skinhil.model.timeline.Timeline`'s file mode). The trials are the board's own: its
stimulus onset markers (classification) and the :class:`~skinhil.scoring.TaskScoreboard`
fed the contacts' truth at the start of every 1 ms tick, as the board's scoring participant
feeds it (touches, vibrating touches, slips).

One sample is one trial: the spikes from its onset to the end of its answer window (onset +
the board's response window); a slip's sample starts at the touch-down of its contact, so
its onset lies inside the sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from firmware_sim.config import DEFAULT_RESPONSE_WINDOW_S
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.skin import DEFAULT_AMPLITUDE, SkinModel, SkinParams
from skinhil.model.timeline import DEFAULT_REST_S
from skinhil.receiver.training import board_stream
from skinhil.scoring import TaskScoreboard
from skinhil.scoring.tasks import Trial
from skinhil.suites import Trials
from skinhil.tasks import TrialKind
from skinhil.world import TouchSensor
from skinhil.world.truth import TRUTH_DTYPE, TRUTH_PERIOD_S


@dataclass(frozen=True)
class Sample:
    """One trial of a case: its task, seed, index among the run's samples, window
    ``[start_us, end_us)`` (µs of board time), the spikes in it (``t_us`` µs of board time,
    ``units`` sensor addresses), its class value (a stimulus id, a frequency in Hz; None for
    a task without classes) and the truth the board judges answers against: the contact's
    centroid (mm) and normal force (N) 50 ms after the touch-down, its vibration frequency
    (Hz, 0: none), a slip's onset (µs of board time; None: no slip); NaN where the trial has
    no contact (classification)."""

    case: str
    task: str
    seed: int
    trial: int
    start_us: int
    end_us: int
    t_us: np.ndarray
    units: np.ndarray
    class_value: float | None
    x_mm: float = math.nan
    y_mm: float = math.nan
    force_n: float = math.nan
    frequency_hz: float = 0.0
    slip_us: int | None = None


@dataclass(frozen=True)
class Run:
    """A case's run simulated offline: every spike (``t`` µs, ``addr``), the stimulus
    onsets (µs, stimulus id), the task scoreboard's trials, the contacts' truth per 1 ms tick
    (:data:`~skinhil.world.truth.TRUTH_DTYPE`) and the run's length (µs)."""

    events: np.ndarray
    onsets: list[tuple[int, int]]
    scoreboard: TaskScoreboard | None
    truth: np.ndarray
    end_us: int


def skin_model(size: MeshSize = PAPER_SIZE) -> SkinModel:
    """The board's default skin of top-layer ``size`` (``serve``'s defaults)."""
    return SkinModel(SkinParams.at_amplitude(DEFAULT_AMPLITUDE, size=size))


def simulate(trials: Trials, snr_db: float, dt_s: float = 1e-4,
             size: MeshSize = PAPER_SIZE,
             response_window_s: float = DEFAULT_RESPONSE_WINDOW_S) -> Run:
    """Simulate ``trials`` offline (module docstring) at ``snr_db`` (dB) with step ``dt_s``
    (s), for the run's length plus ``response_window_s`` (s: the last trial's answer
    window)."""
    if trials.grasp is not None:
        raise ConfigError(f"case {trials.case!r} holds an object whose lifts depend on the "
                          "decoder's grip: it has no offline samples; leave it out")
    scene = trials.scenario.scene
    board = None if scene is None else TaskScoreboard(
        [c.trajectory.vibration_frequency_hz if c.trajectory.vibration_amplitude_m > 0
         else 0.0 for c in scene.contacts], response_window_s)
    dt_us = int(round(dt_s * 1e6))
    every = max(1, int(round(TRUTH_PERIOD_S / dt_s)))
    n_total = int(round((trials.duration_s + response_window_s) / dt_s))
    truth = [np.zeros(0, dtype=TRUTH_DTYPE)]

    def observe(touch: TouchSensor, first: int, raw: np.ndarray) -> None:
        """Feed the scoreboard the contacts' truth at the start of every 1 ms tick."""
        assert board is not None
        for k in range((-first) % every, len(raw), every):
            board.observe((first + k) * dt_us, raw[k])
        truth.append(touch.truth_at(raw, first, every))

    events = []
    onsets: list[tuple[int, int]] = []
    for ev, markers, _ in board_stream(n_total * dt_s, snr_db, DEFAULT_REST_S, trials.seed,
                                       dt_s, trials.scenario.schedule, size, scene,
                                       on_contacts=observe):
        events.append(ev)
        onsets += [(m.t_us, m.stimulus_id) for m in markers if m.phase == "onset"]
    if board is not None:
        board.advance(n_total * dt_us)
    return Run(np.concatenate(events), onsets, board, np.concatenate(truth),
               n_total * dt_us)


def case_samples(trials: Trials, snr_db: float, dt_s: float = 1e-4,
                 size: MeshSize = PAPER_SIZE,
                 response_window_s: float = DEFAULT_RESPONSE_WINDOW_S) -> list[Sample]:
    """The samples of ``trials`` (a case's trials of one seed): one per trial of the task
    the case poses, simulated by :func:`simulate`."""
    if len(trials.tasks) != 1:
        raise ConfigError(f"case {trials.case!r} poses {len(trials.tasks)} tasks; a dataset "
                          "takes the cases that pose one")
    run = simulate(trials, snr_db, dt_s, size, response_window_s)
    task = trials.tasks[0].name
    window_us = int(round(response_window_s * 1e6))
    ev = run.events

    def sample(i: int, start: int, end: int, value: float | None, **truth: object) -> Sample:
        lo, hi = np.searchsorted(ev["t"], [start, end])
        return Sample(trials.case, task, trials.seed, i, start, end,
                      ev["t"][lo:hi].astype(np.int64), ev["addr"][lo:hi].astype(np.uint16),
                      value, **truth)  # type: ignore[arg-type]

    if run.scoreboard is None:
        return [sample(i, t, t + window_us, float(sid))
                for i, (t, sid) in enumerate(run.onsets)]
    scores = {s.task.name: s for s in run.scoreboard.tasks.values()}
    if task not in scores:
        raise ConfigError(f"case {trials.case!r} poses {task!r}, which its scene gives no "
                          "trial of")
    touches = next(s.trials for s in run.scoreboard.tasks.values()
                   if s.task.trials is TrialKind.TOUCH)
    classes = bool(trials.tasks[0].classes)
    out = []
    for i, trial in enumerate(scores[task].trials):
        down = _touch_of(touches, trial)
        x, y, n = down.sample if down.sample is not None else (down.x_mm, down.y_mm,
                                                                  down.normal_n)
        slip = trial.t0_us if scores[task].task.trials is TrialKind.SLIP else None
        out.append(sample(i, down.t0_us, trial.t0_us + window_us,
                          trial.frequency_hz if classes else None, x_mm=x, y_mm=y,
                          force_n=n, frequency_hz=trial.frequency_hz, slip_us=slip))
    return out


def _touch_of(touches: list[Trial], trial: Trial) -> Trial:
    """The touch of ``trial``'s contact that began last at or before ``trial``'s onset."""
    mine = [t for t in touches if t.contact == trial.contact and t.t0_us <= trial.t0_us]
    if not mine:  # the scoreboard opens a touch before any slip of its contact
        raise AssertionError(f"no touch before the trial at {trial.t0_us} µs")
    return mine[-1]
