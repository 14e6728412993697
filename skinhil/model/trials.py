"""Many noisy trials of many stimuli, fast: mechanics once per stimulus, neurons per trial.

The mechanics are deterministic, so each stimulus's spring forces are computed once and
shared by its repetitions; only the neuron noise differs between repetitions. The neurons
run in blocks of ``BLOCK_STEPS`` steps; :func:`simulate_trials` fills a dense bool raster
(n_stim x reps x n_steps x n_channels: 760 MB for 9 x 50 trials of 0.5 s at 6x6), while
:func:`simulate_trial_events` keeps only the spikes, as events, so its memory is the spring
forces of one stimulus, one block of spikes and the events themselves, at any mesh size.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np
from tqdm.auto import tqdm

from skinhil.errors import ConfigError
from skinhil.events import make_events
from skinhil.model.neurons import IzhikevichParams, NeuronPopulation, NoiseParams, _dt_us
from skinhil.model.skin import SkinModel
from skinhil.model.stimuli import Stimulus

BLOCK_STEPS = 500
"""Steps of spikes held at a time (a block of 50 trials at 6x6 is 8.5 MB of bools)."""


def _check_reps(reps: int) -> int:
    if not (isinstance(reps, int | np.integer) and reps > 0):
        raise ConfigError(f"reps must be a positive integer, got {reps!r}")
    return int(reps)


def _spike_blocks(stimuli: Sequence[Stimulus], reps: int, duration_s: float, dt_s: float,
                  snr_db: float, seed: int | None, model: SkinModel | None,
                  params: IzhikevichParams | None, progress: bool,
                  noise: NoiseParams | None) -> Iterator[tuple[int, int, np.ndarray]]:
    """``(stimulus index, first step, spikes (n, reps, n_channels) bool)`` block by block."""
    model = model or SkinModel()
    streams = np.random.SeedSequence(seed).spawn(len(stimuli))
    for i in tqdm(range(len(stimuli)), desc="trials", unit="stimulus", disable=not progress):
        forces = model.simulate(stimuli[i], duration_s, dt_s)
        pop = NeuronPopulation(model.n_springs, params, snr_db, streams[i], batch=int(reps),
                               noise=noise)
        for start in range(0, forces.shape[0], BLOCK_STEPS):
            yield i, start, pop.step_block(forces[start:start + BLOCK_STEPS], dt_s)


def simulate_trials(stimuli: Sequence[Stimulus], reps: int, duration_s: float = 0.5,
                    dt_s: float = 1e-4, snr_db: float = math.inf, seed: int | None = 0,
                    model: SkinModel | None = None, params: IzhikevichParams | None = None,
                    progress: bool = False, noise: NoiseParams | None = None,
                    channels: Sequence[int] | None = None) -> np.ndarray:
    """Bool spike raster (n_stim, reps, n_steps, n_channels) of ``reps`` noisy trials per
    stimulus (n_channels = the model's springs, 338 at 6x6).

    ``channels`` (0-based sensor indices) keeps only those columns of the raster (the last
    axis then has ``len(channels)`` entries); the trials are the same as without it.

    Every trial starts from rest; stimulus ``i`` repetition ``r`` draws noise from its own
    stream derived from ``seed``, so results are reproducible and independent of ``reps``
    ordering. ``noise`` says how ``snr_db`` becomes noise (:class:`NoiseParams`).
    """
    reps = _check_reps(reps)
    model = model or SkinModel()
    n_steps = max(1, int(round(duration_s / dt_s))) if duration_s > 0 else 0
    n_ch = model.n_springs
    keep = np.arange(n_ch) if channels is None else np.asarray(channels, dtype=np.int64)
    if keep.ndim != 1 or keep.size == 0 or keep.min() < 0 or keep.max() >= n_ch:
        raise ConfigError(f"channels must be 0-based sensor indices in 0..{n_ch - 1}, "
                          f"got {channels!r}")
    out = np.empty((len(stimuli), reps, n_steps, keep.size), dtype=np.bool_)
    for i, start, spikes in _spike_blocks(stimuli, reps, duration_s, dt_s, snr_db, seed, model,
                                          params, progress, noise):
        kept = spikes if channels is None else spikes[:, :, keep]
        out[i, :, start:start + spikes.shape[0]] = kept.transpose(1, 0, 2)
    return out


def simulate_trial_events(stimuli: Sequence[Stimulus], reps: int, duration_s: float = 0.5,
                          dt_s: float = 1e-4, snr_db: float = math.inf, seed: int | None = 0,
                          model: SkinModel | None = None,
                          params: IzhikevichParams | None = None, progress: bool = False,
                          noise: NoiseParams | None = None) -> list[list[np.ndarray]]:
    """The same trials as :func:`simulate_trials` (same arguments, same spikes), as events:
    ``out[i][r]`` is the event array (:data:`skinhil.events.EVENT_DTYPE`, µs from the trial's
    start, sorted by time then address) of stimulus ``i``, repetition ``r``."""
    reps = _check_reps(reps)
    dt_us = _dt_us(dt_s)
    parts: list[list[list[np.ndarray]]] = [[[] for _ in range(reps)] for _ in stimuli]
    for i, start, spikes in _spike_blocks(stimuli, reps, duration_s, dt_s, snr_db, seed, model,
                                          params, progress, noise):
        rep_major = spikes.transpose(1, 0, 2)
        for r in range(rep_major.shape[0]):
            steps, addr = np.nonzero(rep_major[r])
            parts[i][r].append(make_events((start + steps) * dt_us, addr))
    return [[np.concatenate(p) if p else make_events(np.zeros(0), np.zeros(0)) for p in trial]
            for trial in parts]
