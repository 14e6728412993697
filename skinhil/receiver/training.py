"""Fit the receiver's direction decoder on the windows it will see online.

Protocol (what the board does, simulated offline and faster than real time):

1. a continuous board stream: a seeded random sequence of the 9 direction conditions
   (classes 0..8), like the board's default one but balanced (each condition ``reps`` times,
   shuffled, :func:`balanced_schedule`), ``rest_s`` of rest after each, played by the board's
   own :class:`skinhil.model.timeline.Timeline` (same markers) and felt by one
   :class:`skinhil.model.sensor.SkinSensor` at ``snr_db`` — so every stimulus starts from the state
   the previous one left (adaptation, noise, PSP tails);
2. its spikes, as events, go through the receiver's own onset and window code
   (:class:`~skinhil.receiver.online.OnsetWindows`): windows start at the *detected* onset;
3. each window is labelled by the ground-truth marker it matches under the scoring rule of
   :mod:`skinhil.receiver.scoring` (false alarms give no window, missed markers are counted);
4. features and classifier are :mod:`skinhil.decoding`'s (time-binned PSP activity of all
   sensors — 338 at 6x6 — linear SVM); repeated stratified cross-validation on the labelled windows
   gives the window accuracy and confusion matrix.

The offline **accuracy** is the cross-validated window accuracy times the fraction of scored
markers that got a window (misses count as wrong): the same definition as the online
accuracy. A class with fewer than ``CV_FOLDS`` detected windows (possible when the weakest,
0.1 N, stimuli are rarely detected) is left out of the decoder; its windows count as wrong
offline, as they must be online. The training stream's seed is ``TRAIN_SEED_BASE + seed``
so it never coincides with a board run at a small seed.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from skinhil.decoding import DirectionDecoder, FeatureSpec, cross_validate
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize, spring_count
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule, ScheduledStimulus, at_size, direction_conditions
from skinhil.model.timeline import DEFAULT_REST_S, MarkerEvent, Timeline
from skinhil.receiver.online import OnsetWindows
from skinhil.receiver.params import ReceiverParams
from skinhil.receiver.scoring import scoreboard_for
from skinhil.world import Scene, TouchSensor

log = logging.getLogger(__name__)

WINDOW_S = 0.05
"""Decision window (s) after the onset: the evoked spikes come within ~20 ms."""
BIN_S = 0.01
"""Feature time bin (s)."""
CV_FOLDS = 5
CV_REPEATS = 3
TRAIN_SEED_BASE = 10_000
"""Added to the training seed for the simulated stream (board runs use small seeds)."""
LEAD_S = 0.1
"""Board time (s) before the first stimulus of the board's random schedule."""
BLOCK_S = 0.5
"""Board time (s) simulated per block."""


@dataclass(frozen=True)
class StreamWindows:
    """Labelled windows of one simulated board stream and how its markers were scored."""

    features: np.ndarray
    """(n_windows, n_features) decoder features of the windows matched to a marker."""
    labels: np.ndarray
    """(n_windows,) true class of each window."""
    markers: int
    """Onset markers scored (matched + missed)."""
    misses: int
    false_alarms: int
    spec: FeatureSpec
    snr_db: float
    rest_s: float
    n_stimuli: int
    seed: int


@dataclass(frozen=True)
class TrainingReport:
    """Offline figures (fractions 0..1) on the training stream, same rule as online."""

    snr_db: float
    rest_s: float
    n_stimuli: int
    seed: int
    markers: int
    windows: int
    """Windows matched to a marker."""
    decodable_windows: int
    """Of those, windows of the classes the decoder learned (at least ``CV_FOLDS`` windows
    each); the others can only be wrong."""
    misses: int
    false_alarms: int
    window_accuracy: float
    """Cross-validated accuracy on the decodable windows."""
    window_accuracy_std: float
    confusion: np.ndarray
    """Summed over folds and repeats; rows true class, columns predicted (``classes``)."""
    classes: tuple[int, ...]

    @property
    def accuracy(self) -> float:
        """Offline accuracy by the scoring rule: correct windows / scored markers, with the
        cross-validated window accuracy on the decodable windows (the others, and the
        missed markers, count as wrong)."""
        if self.markers == 0:
            return math.nan
        if self.decodable_windows == 0:
            return 0.0
        return self.window_accuracy * self.decodable_windows / self.markers


def feature_spec(dt_s: float = 1e-4, size: MeshSize = PAPER_SIZE) -> FeatureSpec:
    """The receiver's feature definition: all sensors of a skin of top-layer ``size`` (338 at
    6x6), ``WINDOW_S`` in ``BIN_S`` bins."""
    return FeatureSpec(dt_s=dt_s, window_s=WINDOW_S, bin_s=BIN_S,
                       n_channels=spring_count(size))


def stream_duration_s(n_stimuli: int, rest_s: float) -> float:
    """Board time (s) a random schedule of ``n_stimuli`` stimuli needs (the board's lead)."""
    return LEAD_S + n_stimuli * (direction_conditions()[0].end_s + rest_s)


def balanced_schedule(reps: int, rest_s: float, seed: int,
                      size: MeshSize = PAPER_SIZE) -> Schedule:
    """Each direction condition ``reps`` times in a seeded random order, ``rest_s`` (s) of
    rest after each, the first at ``LEAD_S`` (as the board's random schedule), on a skin of
    top-layer ``size``."""
    conditions = [at_size(c, size) for c in direction_conditions()]
    order = np.random.default_rng(seed).permutation(np.repeat(np.arange(len(conditions)),
                                                               reps))
    entries, t = [], LEAD_S
    for sid in order:
        stim = conditions[int(sid)]
        entries.append(ScheduledStimulus(t, stim, int(sid)))
        t += stim.end_s + rest_s
    return Schedule(tuple(entries))


def board_stream(duration_s: float, snr_db: float, rest_s: float, seed: int,
                 dt_s: float = 1e-4, schedule: Schedule | None = None,
                 size: MeshSize = PAPER_SIZE, scene: Scene | None = None,
                 on_contacts: Callable[[TouchSensor, int, np.ndarray], None] | None = None,
                 ) -> Iterator[tuple[np.ndarray, list[MarkerEvent], int]]:
    """The board's stream simulated offline: per block (events, markers, block end µs).

    Same schedule (the board's :class:`Timeline`: its random one for ``seed`` and
    ``rest_s``, or ``schedule`` played once, with the contacts of ``scene`` touching the skin
    from the start) and same sensor (:class:`SkinSensor` seeded ``seed``) as ``skinhil serve
    --seed seed --rest rest_s --size size [--schedule ...]``. With a scene,
    ``on_contacts(touch, first, raw)`` sees each block's contact states (``raw``, one row per
    step from step ``first``) before the block is yielded.
    """
    sensor = SkinSensor(SkinModel(SkinParams(size=size)), dt_s=dt_s, snr_db=snr_db, seed=seed,
                        state_forces=scene is not None)
    touch = TouchSensor(sensor, scene) if scene is not None else None
    if touch is not None:
        touch.start(0.0)
        schedule = schedule or Schedule(())
    timeline = Timeline(dt_s, schedule, seed=seed, rest_s=rest_s,
                        mode=Timeline.SCHEDULE_RANDOM if schedule is None
                        else Timeline.SCHEDULE_FILE, size=size)
    dt_us = int(round(dt_s * 1e6))
    n_total = int(round(duration_s / dt_s))
    block = max(1, int(round(BLOCK_S / dt_s)))
    for first in range(0, n_total, block):
        n = min(block, n_total - first)
        playing = timeline.schedule_for(first * dt_s, (first + n - 1) * dt_s)
        if touch is None:
            _, spikes = sensor.advance_schedule(playing, n)
        else:
            _, spikes, raw = touch.advance_schedule(playing, n)
            if on_contacts is not None:
                on_contacts(touch, first, raw)
        end_us = (first + n) * dt_us
        yield sensor.events(spikes, first), timeline.markers_before(end_us), end_us


def stream_windows(n_stimuli: int, snr_db: float, rest_s: float, seed: int,
                   dt_s: float = 1e-4, params: ReceiverParams | None = None,
                   progress: bool = False, balanced: bool = True,
                   board_seed: int | None = None,
                   size: MeshSize = PAPER_SIZE,
                   scenario: tuple[Schedule, Scene | None] | None = None) -> StreamWindows:
    """Cut a simulated board stream into the receiver's windows and label them.

    ``balanced``: the stimuli are :func:`balanced_schedule` (``n_stimuli`` a multiple of 9),
    else the board's own random schedule for the stream seed. The stream seed is
    ``TRAIN_SEED_BASE + seed``, or ``board_seed`` to replay exactly what ``skinhil serve
    --seed board_seed --rest rest_s`` plays (with ``balanced=False``). A ``scenario`` (a
    schedule file's stimuli and contacts) is played once instead, as ``skinhil serve
    --schedule FILE`` plays it: its stimuli are the classes.
    """
    p = params or ReceiverParams()
    spec = feature_spec(dt_s, size)
    windows = OnsetWindows(dt_s, spec.n_channels, spec.psp, spec.n_steps, p.onset)
    board = scoreboard_for(tuple(range(len(direction_conditions()))), windows,
                           p.match_window_s)
    xs: list[np.ndarray] = []
    ys: list[int] = []
    duration = stream_duration_s(n_stimuli, rest_s)
    stream_seed = TRAIN_SEED_BASE + seed if board_seed is None else board_seed
    n_cond = len(direction_conditions())
    if balanced and n_stimuli % n_cond:
        raise ConfigError(f"a balanced stream needs a multiple of {n_cond} stimuli, "
                          f"got {n_stimuli}")
    schedule = (balanced_schedule(n_stimuli // n_cond, rest_s, stream_seed, size) if balanced
                else None)
    scene = None
    if scenario is not None:
        schedule, scene = scenario
        classes = tuple(sorted({e.stimulus_id for e in schedule.entries}))
        board = scoreboard_for(classes, windows, p.match_window_s)
        duration = max(schedule.duration_s, scene.duration_s if scene else 0.0) + WINDOW_S
        n_stimuli = len(schedule.entries)
    blocks = board_stream(duration, snr_db, rest_s, stream_seed, dt_s, schedule, size, scene)
    bar = tqdm(total=round(duration, 1), desc="simulating the board stream", unit="s",
               disable=not progress, bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s board time")
    for events, markers, end_us in blocks:
        for m in markers:
            if m.phase == "onset":
                board.add_marker(m.t_us, m.stimulus_id)
        windows.push(events)
        for w in windows.advance(end_us):
            onset = board.claim((w.start_step + windows.window_steps) * windows.dt_us)
            if onset is not None:
                xs.append(spec.transform(w.psp))
                ys.append(onset.stimulus_id)
        board.resolve(windows.board_time_us)
        bar.update(round(end_us * 1e-6 - bar.n, 3))
    bar.close()
    x = np.array(xs) if xs else np.zeros((0, spec.n_features))
    return StreamWindows(x, np.array(ys, dtype=np.int64), len(ys) + board.misses,
                         board.misses, board.false_alarms, spec, snr_db, rest_s, n_stimuli,
                         seed)


def stream_accuracy(decoder: DirectionDecoder, sw: StreamWindows) -> float:
    """Accuracy of a fitted ``decoder`` on the windows of one stream by the scoring rule:
    correct windows / scored markers (missed markers count as wrong)."""
    if sw.markers == 0:
        return math.nan
    if sw.labels.size == 0:
        return 0.0
    return int(np.sum(decoder.predict(sw.features) == sw.labels)) / sw.markers


def fit_windows(sw: StreamWindows, cross_validation: bool = True
                ) -> tuple[DirectionDecoder | None, TrainingReport]:
    """Cross-validate and fit a decoder on labelled windows; the report in any case.

    Classes with fewer than ``CV_FOLDS`` windows are left out (their windows count as wrong);
    with fewer than two classes left no decoder can be fitted (None; the report's accuracy
    then counts every scored marker as wrong).
    """
    classes, counts = np.unique(sw.labels, return_counts=True)
    need = CV_FOLDS if cross_validation else 1
    kept = classes[counts >= need]
    use = np.isin(sw.labels, kept) if kept.size >= 2 else np.zeros(sw.labels.size, bool)
    if 0 < use.sum() < use.size:
        left_out = sorted(set(classes.tolist()) - set(kept.tolist()))
        log.warning("classes %s have fewer than %d detected windows and are left out of the "
                    "decoder; their %d windows count as wrong", left_out, need,
                    int((~use).sum()))
    x, y = sw.features[use], sw.labels[use]
    acc, std = math.nan, math.nan
    conf = np.zeros((kept.size, kept.size), dtype=np.int64)
    decoder = None
    if use.any():
        if cross_validation:
            cv = cross_validate(DirectionDecoder(sw.spec), x, y, folds=CV_FOLDS,
                                repeats=CV_REPEATS, seed=sw.seed)
            acc, std, conf = cv.accuracy, cv.accuracy_std, cv.confusion
        decoder = DirectionDecoder(sw.spec).fit(x, y)
    report = TrainingReport(sw.snr_db, sw.rest_s, sw.n_stimuli, sw.seed, sw.markers,
                            int(sw.labels.size), int(use.sum()), sw.misses, sw.false_alarms,
                            float(acc), float(std), np.asarray(conf),
                            tuple(int(c) for c in kept) if use.any() else ())
    return decoder, report


def train_decoder(snr_db: float = 10.0, reps: int = 50, seed: int = 0, dt_s: float = 1e-4,
                  rest_s: float = DEFAULT_REST_S, progress: bool = False,
                  cross_validation: bool = True,
                  size: MeshSize = PAPER_SIZE,
                  scenario: tuple[Schedule, Scene | None] | None = None
                  ) -> tuple[DirectionDecoder, TrainingReport]:
    """Simulate ``9·reps`` board stimuli (each condition ``reps`` times) on a skin of
    top-layer ``size``, or a ``scenario`` file's stimuli and contacts played once
    (:func:`stream_windows`), cut and label windows, cross-validate and fit
    (:func:`fit_windows`).

    Raises ConfigError when the onset detector matched too few windows to fit a decoder (at
    such a noise level nothing can be decoded online either).
    """
    if scenario is not None and not scenario[0].entries:
        raise ConfigError("the scenario has no stimuli ([[event]] tables) to learn: train "
                          "needs stimuli to label its windows")
    sw = stream_windows(9 * reps, snr_db, rest_s, seed, dt_s, progress=progress, size=size,
                        balanced=scenario is None, scenario=scenario)
    decoder, report = fit_windows(sw, cross_validation)
    if decoder is None:
        classes, counts = np.unique(sw.labels, return_counts=True)
        raise ConfigError(
            f"at {snr_db:g} dB the onset detector matched only {sw.labels.size} of "
            f"{sw.markers} stimuli ({dict(zip(classes.tolist(), counts.tolist(), strict=True))}"
            f" windows per class); need {CV_FOLDS} windows for each of at least two classes: "
            + ("give the schedule more stimuli or raise the SNR" if scenario is not None
               else "raise --reps or the SNR"))
    return decoder, report
