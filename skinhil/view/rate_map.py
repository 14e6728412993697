"""The live view's skin map: each place's spike rate against its sensors' own baseline.

At the defaults (6x6, 10 dB) every neuron fires noise spikes at about 1 Hz and a touch adds
a few to a few tens of spikes per second to a handful of sensors: a map of raw rates is an
even dark red with the touch lost in it. The map therefore shows, per place, how far the
recent rate stands above what those sensors fire at rest, in standard deviations of the
noise (a z-score), so a touch stands out of the noise at any SNR and any skin size.

Per sensor ``c`` (rates in spikes/s, times in board seconds):

- the recent rate ``r_c``: an exponential average of its rate over :data:`FAST_TAU_S`
  (``r ← r·a + (1 − a)·k/dt``, ``a = exp(−dt/τ)``, for ``k`` spikes in ``dt``: unbiased,
  its variance at a Poisson rate ``λ`` about ``λ/(2τ)``);
- the baseline ``b_c``: its spikes over the time it was at rest, both forgotten over
  :data:`BASELINE_TAU_S` (the SNR may change), shrunk towards ``m``, the mean rate of every
  sensor over all the time (touched or not: a touch moves the mean of hundreds of sensors
  little), by :data:`PRIOR_S` seconds of it (a sensor seen for a second gets the skin's
  mean): ``b_c = (n_c + m·T0) / (T_c + T0)``, at least
  :data:`MIN_BASELINE_HZ``; a sensor is at rest while its place's z is below
  :data:`TOUCH_Z`, so a touch does not raise its own baseline;
- a place is a half-cell of the top layer (the sensors whose springs' midpoints lie there,
  :func:`skinhil.view.feed.grid_xy`); its z is ``Σ(r_c − b_c) / sqrt(Σ b_c / (2τ))`` over
  the sensors of the place and of its 8 neighbours (a place at the edge holds one or two
  sensors, too few for a rate to mean anything; a touch spans more than one place): the
  excess of those sensors over their baselines in units of the standard deviation of a
  Poisson rate averaged over ``τ`` at those baselines.

:meth:`RateMap.advance` takes a board time and the events since the last call, and gives
the places' z and mean rate as row-major ``(rows, cols)`` float32 arrays.
"""

from __future__ import annotations

import math

import numpy as np

FAST_TAU_S = 0.25
"""Board seconds of the recent rate's average (the touches of the built-in stimuli last
0.25 s of indentation)."""

BASELINE_TAU_S = 30.0
"""Board seconds over which the baseline forgets."""

PRIOR_S = 2.0
"""Seconds of the skin's mean rate each sensor's baseline starts from."""

MIN_BASELINE_HZ = 0.05
"""Lowest baseline (spikes/s): a silent sensor's first spike is not a touch."""

TOUCH_Z = 3.0
"""A place whose z is at or above this is touched: its sensors' baselines wait."""


def place_bins(sensor_xy: np.ndarray, grid: tuple[int, int]) -> tuple[np.ndarray, int, int]:
    """(bin of each sensor, bin rows, bin cols): the half-cells of a top layer of ``grid``
    (rows, cols) masses that hold each sensor's place (``sensor_xy``: column, row in grid
    units from the top-left mass)."""
    rows, cols = grid
    bw, bh = max(1, 2 * (cols - 1)), max(1, 2 * (rows - 1))
    bx = np.clip(np.floor(2 * sensor_xy[:, 0]).astype(np.int64), 0, bw - 1)
    by = np.clip(np.floor(2 * sensor_xy[:, 1]).astype(np.int64), 0, bh - 1)
    return by * bw + bx, bh, bw


class RateMap:
    """The places' rate above their sensors' baselines (see the module)."""

    def __init__(self, sensor_xy: np.ndarray, grid: tuple[int, int]) -> None:
        self.bin_of, self.rows, self.cols = place_bins(sensor_xy, grid)
        n = int(sensor_xy.shape[0])
        self.n_channels = n
        self._per_bin = np.bincount(self.bin_of, minlength=self.rows * self.cols)
        self.rate_hz = np.zeros(n)
        """Each sensor's recent rate (spikes/s)."""
        self._rest_spikes = np.zeros(n)
        self._rest_s = np.zeros(n)
        self._all_spikes = 0.0
        self._all_s = 0.0
        self._t_us: int | None = None
        self._pending = np.zeros(n)
        self.z = np.zeros((self.rows, self.cols), dtype=np.float32)
        """Each place's z (see the module), as of the last :meth:`advance`."""
        self.place_rate_hz = np.zeros((self.rows, self.cols), dtype=np.float32)
        """Each place's mean recent rate (spikes/s per sensor)."""

    def add(self, addr: np.ndarray) -> None:
        """Count the spikes of sensor addresses ``addr`` (out-of-range ones left out)."""
        a = np.asarray(addr, dtype=np.int64)
        a = a[(a >= 0) & (a < self.n_channels)]
        self._pending += np.bincount(a, minlength=self.n_channels)

    def baseline_hz(self) -> np.ndarray:
        """Each sensor's baseline rate (spikes/s)."""
        mean = self._all_spikes / (self._all_s * self.n_channels) if self._all_s > 0 else 0.0
        b = (self._rest_spikes + mean * PRIOR_S) / (self._rest_s + PRIOR_S)
        return np.maximum(b, MIN_BASELINE_HZ)

    def _pooled(self, per_place: np.ndarray) -> np.ndarray:
        """Each place's sum over itself and its 8 neighbours (flat, row-major)."""
        grid = np.pad(per_place.reshape(self.rows, self.cols), 1)
        out = sum(grid[dy:dy + self.rows, dx:dx + self.cols]
                  for dy in range(3) for dx in range(3))
        return np.asarray(out).ravel()

    def advance(self, t_us: int) -> None:
        """Move to board time ``t_us`` with the spikes added since the last call: the recent
        rates, the places' z and the baselines of the sensors at rest."""
        k, self._pending = self._pending, np.zeros(self.n_channels)
        if self._t_us is None:  # the first call only starts the clock
            self._t_us = int(t_us)
            return
        if int(t_us) <= self._t_us:  # no board time passed: the spikes wait for some
            self._pending += k
            return
        dt = (int(t_us) - self._t_us) * 1e-6
        self._t_us = int(t_us)
        keep = math.exp(-dt / FAST_TAU_S)
        self.rate_hz = self.rate_hz * keep + k * (1 - keep) / dt
        base = self.baseline_hz()
        size = self.rows * self.cols
        excess = self._pooled(np.bincount(self.bin_of, self.rate_hz - base, minlength=size))
        var = self._pooled(np.bincount(self.bin_of, base, minlength=size)) / (2 * FAST_TAU_S)
        z = np.where(var > 0, excess / np.sqrt(np.maximum(var, 1e-12)), 0.0)
        mean = np.bincount(self.bin_of, self.rate_hz, minlength=size) / np.maximum(
            self._per_bin, 1)
        self.z = z.reshape(self.rows, self.cols).astype(np.float32)
        self.place_rate_hz = mean.reshape(self.rows, self.cols).astype(np.float32)
        rest = z[self.bin_of] < TOUCH_Z
        forget = math.exp(-dt / BASELINE_TAU_S)
        self._rest_spikes *= forget
        self._rest_s *= forget
        self._all_spikes = self._all_spikes * forget + float(k.sum())
        self._all_s = self._all_s * forget + dt
        self._rest_spikes[rest] += k[rest]
        self._rest_s[rest] += dt
