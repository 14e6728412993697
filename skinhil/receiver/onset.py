"""Stimulus onset from the activity alone: a population spike-count threshold.

The rule, per simulation step ``k`` (board time ``k·dt``):

1. ``c[k]`` = number of spikes of all channels in the last ``W = window_s/dt`` steps
   (steps ``k−W+1 .. k``);
2. a running baseline of ``c`` (mean ``μ`` and standard deviation ``σ``, exponential
   weighting with time constant ``baseline_tau_s``) is kept from the steps outside the
   refractory periods (the warm-up ``warmup_s`` only learns it); it is updated at the end
   of every ``UPDATE_S`` of board time (blocks aligned to absolute step numbers), so the
   threshold is fixed within such a block and the result does not depend on how the stream
   was chunked;
3. an onset is detected at the first step with ``c[k] ≥ μ + max(z·σ, min_excess_spikes)``,
   after the warm-up and outside the refractory period (``refractory_s`` after the previous
   onset).

Without noise the baseline is silent, so any ``min_excess_spikes`` spikes within
``window_s`` mark an onset; with noise the threshold rises with the noise-driven rate and
weak stimuli whose few evoked spikes stay under it are missed (and counted as such).
No ground truth is used. The same class serves offline trials and the online stream.
"""

from __future__ import annotations

import math

import numpy as np

from skinhil.receiver.params import OnsetParams

UPDATE_S = 0.01
"""Board time (s) between baseline updates."""


class OnsetDetector:
    """Population-count onset detector stepping on board time at step ``dt_s`` (s)."""

    def __init__(self, dt_s: float, params: OnsetParams | None = None) -> None:
        self.params = params or OnsetParams()
        self.dt_s = float(dt_s)
        p = self.params
        self.window_steps = max(1, int(round(p.window_s / dt_s)))
        self.warmup_steps = int(round(p.warmup_s / dt_s))
        self.refractory_steps = max(1, int(round(p.refractory_s / dt_s)))
        self._alpha = dt_s / p.baseline_tau_s
        self.update_steps = max(1, int(round(UPDATE_S / dt_s)))
        self.reset()

    def reset(self) -> None:
        """Forget the baseline and the stream position (next step is step 0)."""
        self.step_index = 0
        self._tail = np.zeros(self.window_steps - 1)
        self._mean = 0.0
        self._sq = 0.0
        self._n_base = 0
        self._refractory_until = 0
        self._pending = np.zeros(3)  # baseline steps, sum, sum of squares since last update

    @property
    def threshold(self) -> float:
        """The current onset threshold on the window count (spikes)."""
        p = self.params
        sd = math.sqrt(max(self._sq - self._mean ** 2, 0.0))
        return self._mean + max(p.z * sd, p.min_excess_spikes)

    def process(self, population_counts: np.ndarray) -> list[int]:
        """Feed the population spike counts of the next steps; return onset step indices.

        ``population_counts`` is (n_steps,) spikes summed over channels per step; the returned
        indices are absolute step numbers since the last reset.
        """
        x = np.asarray(population_counts, dtype=np.float64)
        onsets: list[int] = []
        j = 0
        while j < x.shape[0]:
            u = self.update_steps
            end = min(x.shape[0], j + u - (self.step_index % u))
            onsets += self._process_block(x[j:end])
            j = end
        return onsets

    def _process_block(self, x: np.ndarray) -> list[int]:
        n = x.shape[0]
        start = self.step_index
        w = self.window_steps
        joined = np.concatenate([self._tail, x])
        csum = np.concatenate([[0.0], np.cumsum(joined)])
        counts = csum[w:] - csum[:-w]  # counts[j]: the window ending at step start + j
        self._tail = joined[len(joined) - (w - 1):]
        thr = self.threshold
        steps = start + np.arange(n)
        baseline = steps >= self._refractory_until
        onsets: list[int] = []
        pos = 0
        while True:
            lo = max(pos, self.warmup_steps - start, self._refractory_until - start)
            if lo >= n:
                break
            above = np.flatnonzero(counts[lo:] >= thr)
            if above.size == 0:
                break
            hit = lo + int(above[0])
            onsets.append(start + hit)
            self._refractory_until = start + hit + self.refractory_steps
            # the refractory period leaves the baseline; the steps before the onset stay in
            # it (whether they could be excluded would depend on where the chunk began)
            baseline &= ~((steps >= start + hit) & (steps < self._refractory_until))
            pos = hit + 1
        vals = counts[baseline]
        self._pending += (vals.shape[0], float(vals.sum()), float(np.sum(vals ** 2)))
        self.step_index = start + n
        if self.step_index % self.update_steps == 0:
            self._update_baseline()
        return onsets

    def _update_baseline(self) -> None:
        m = int(self._pending[0])
        mean, sq = self._pending[1:] / max(m, 1)
        self._pending[:] = 0.0
        if m == 0:
            return
        # exponential weighting over steps; a plain running mean until tau's worth of steps
        weight = 1.0 - (1.0 - self._alpha) ** m
        weight = max(weight, m / (self._n_base + m)) if self._n_base * self._alpha < 1.0 \
            else weight
        self._mean += weight * (float(mean) - self._mean)
        self._sq += weight * (float(sq) - self._sq)
        self._n_base += m
