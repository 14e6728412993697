"""Many noisy trials of many stimuli, fast: mechanics once per stimulus, neurons per trial.

The mechanics are deterministic, so each stimulus's spring forces are computed once and
shared by its repetitions; only the neuron noise differs between repetitions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from tqdm.auto import tqdm

from skinhil.errors import ConfigError
from skinhil.neurons import IzhikevichParams, NeuronPopulation, NoiseParams
from skinhil.skin import SkinModel
from skinhil.stimuli import Stimulus


def simulate_trials(stimuli: Sequence[Stimulus], reps: int, duration_s: float = 0.5,
                    dt_s: float = 1e-4, snr_db: float = math.inf, seed: int | None = 0,
                    model: SkinModel | None = None, params: IzhikevichParams | None = None,
                    progress: bool = False, noise: NoiseParams | None = None) -> np.ndarray:
    """Bool spike raster (n_stim, reps, n_steps, 338) of ``reps`` noisy trials per stimulus.

    Every trial starts from rest; stimulus ``i`` repetition ``r`` draws noise from its own
    stream derived from ``seed``, so results are reproducible and independent of ``reps``
    ordering. ``noise`` says how ``snr_db`` becomes noise (:class:`NoiseParams`).
    """
    if not (isinstance(reps, int | np.integer) and reps > 0):
        raise ConfigError(f"reps must be a positive integer, got {reps!r}")
    model = model or SkinModel()
    forces = model.simulate_many(stimuli, duration_s, dt_s)
    n_stim, n_steps, n_ch = forces.shape
    out = np.empty((n_stim, reps, n_steps, n_ch), dtype=np.bool_)
    streams = np.random.SeedSequence(seed).spawn(n_stim)
    for i in tqdm(range(n_stim), desc="trials", unit="stimulus", disable=not progress):
        pop = NeuronPopulation(n_ch, params, snr_db, streams[i], batch=int(reps), noise=noise)
        out[i] = pop.step_block(forces[i], dt_s).transpose(1, 0, 2)
    return out
