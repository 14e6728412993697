"""The paper's post-synaptic-potential kernel (eq. 12) as an exact recursive filter bank.

Kernel, for a spike at ``t*`` (times in ms)::

    a(t) = τm / (τd − τr) · [exp(−(t − t*)/τd) − exp(−(t − t*)/τr)]   for t ≥ t*, else 0

with τd = 4 ms, τr = 12.5 ms, τm = 21.3 ms and latency 0: it peaks at ≈1.0 at ≈6.7 ms and
integrates to τm. As a causal filter it is two first-order exponential states per channel::

    s_d[k] = e^(−dt/τd) s_d[k−1] + n[k],   s_r[k] = e^(−dt/τr) s_r[k−1] + n[k]
    y[k]   = τm / (τd − τr) · (s_d[k] − s_r[k])

where ``n[k]`` counts the channel's spikes stamped at step k (time k·dt). ``y[k]`` is then
exactly the sum of ``a(k·dt − t*)`` over past spikes, at any dt: O(1) per event and
O(channels) per step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from skinhil.errors import ConfigError


@dataclass(frozen=True)
class PSPParams:
    """Time constants of eq. 12 in milliseconds."""

    tau_d_ms: float = 4.0
    tau_r_ms: float = 12.5
    tau_m_ms: float = 21.3

    def __post_init__(self) -> None:
        for name in ("tau_d_ms", "tau_r_ms", "tau_m_ms"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ConfigError(f"PSPParams.{name} must be a finite number > 0, got {value!r}")
        if self.tau_d_ms == self.tau_r_ms:
            raise ConfigError("PSPParams: tau_d_ms and tau_r_ms must differ (eq. 12 divides "
                              "by their difference)")

    @property
    def scale(self) -> float:
        """τm / (τd − τr), unitless."""
        return self.tau_m_ms / (self.tau_d_ms - self.tau_r_ms)


def psp_kernel(t_s: np.ndarray | float, params: PSPParams | None = None) -> np.ndarray:
    """Eq. 12 at lags ``t_s`` (s) after a spike; zero for negative lags."""
    p = params or PSPParams()
    t_ms = np.asarray(t_s, dtype=float) * 1e3
    pos = np.maximum(t_ms, 0.0)
    value = p.scale * (np.exp(-pos / p.tau_d_ms) - np.exp(-pos / p.tau_r_ms))
    return np.where(t_ms >= 0, value, 0.0)


@numba.njit(cache=True)
def _filter_kernel(x: np.ndarray, decay_d: float, decay_r: float, scale: float,
                   sd: np.ndarray, sr: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    # x: (m, n_steps, n) counts of any numeric dtype; sd, sr: (m, n) states, updated
    for b in range(x.shape[0]):
        for k in range(x.shape[1]):
            for i in range(x.shape[2]):
                c = x[b, k, i]
                sd[b, i] = decay_d * sd[b, i] + c
                sr[b, i] = decay_r * sr[b, i] + c
                out[b, k, i] = scale * (sd[b, i] - sr[b, i])


class PSPFilterBank:
    """Eq. 12 filter for ``n_channels`` channels at step ``dt_s`` (s); online and offline."""

    def __init__(self, n_channels: int, dt_s: float, params: PSPParams | None = None) -> None:
        if not (isinstance(dt_s, int | float) and math.isfinite(dt_s) and dt_s > 0):
            raise ConfigError(f"dt_s must be a finite number of seconds > 0, got {dt_s!r}")
        if not (isinstance(n_channels, int | np.integer) and n_channels > 0):
            raise ConfigError(f"n_channels must be a positive integer, got {n_channels!r}")
        self.params = params or PSPParams()
        self.n_channels = int(n_channels)
        self.dt_s = float(dt_s)
        self.decay_d = math.exp(-dt_s * 1e3 / self.params.tau_d_ms)
        self.decay_r = math.exp(-dt_s * 1e3 / self.params.tau_r_ms)
        self._sd = np.zeros(self.n_channels)
        self._sr = np.zeros(self.n_channels)

    def reset(self) -> None:
        """Clear the filter state (no past spikes)."""
        self._sd[:] = 0.0
        self._sr[:] = 0.0

    def step_block(self, counts: np.ndarray) -> np.ndarray:
        """Online: spike counts (n_steps, n) of the next steps → PSP (n_steps, n); keeps state."""
        x = np.asarray(counts)
        if x.ndim != 2 or x.shape[1] != self.n_channels:
            raise ConfigError(f"counts have shape {x.shape}; expected (n_steps, "
                              f"{self.n_channels})")
        out = np.empty((1,) + x.shape)
        sd, sr = self._sd[None], self._sr[None]
        _filter_kernel(x[None], self.decay_d, self.decay_r, self.params.scale, sd, sr, out)
        self._sd, self._sr = sd[0], sr[0]
        return out[0]

    def step(self, counts: np.ndarray) -> np.ndarray:
        """Online: spike counts (n,) of one step → PSP values (n,) at that step."""
        self._sd *= self.decay_d
        self._sr *= self.decay_r
        self._sd += counts
        self._sr += counts
        return np.asarray(self.params.scale * (self._sd - self._sr))

    def filter(self, raster: np.ndarray) -> np.ndarray:
        """Offline, from rest: raster (..., n_steps, n) of spikes or counts (bool or numeric,
        not copied) → PSP of the same shape (float64)."""
        x = np.asarray(raster)
        if x.ndim < 2:
            raise ConfigError(f"raster has shape {x.shape}; expected (..., n_steps, n)")
        flat = x.reshape((-1,) + x.shape[-2:])
        out = np.empty(flat.shape)
        states = np.zeros((flat.shape[0], flat.shape[2]))
        _filter_kernel(flat, self.decay_d, self.decay_r, self.params.scale, states,
                       states.copy(), out)
        return out.reshape(x.shape)
