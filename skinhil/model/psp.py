"""The paper's post-synaptic-potential kernel (eq. 12) as an exact recursive filter bank.

Kernel, for a spike at ``t*`` (times in ms)::

    a(t) = τm / (τd − τr) · [exp(−(t − t*)/τd) − exp(−(t − t*)/τr)]   for t ≥ t*, else 0

with τd = 4 ms, τr = 12.5 ms, τm = 21.3 ms and latency 0: it peaks at ≈1.0 at ≈6.7 ms and
integrates to τm. As a causal filter it is two first-order exponential states per channel::

    s_d[k] = e^(−dt/τd) s_d[k−1] + n[k],   s_r[k] = e^(−dt/τr) s_r[k−1] + n[k]
    y[k]   = τm / (τd − τr) · (s_d[k] − s_r[k])

where ``n[k]`` counts the channel's spikes stamped at step k (time k·dt). ``y[k]`` is then
exactly the sum of ``a(k·dt − t*)`` over past spikes, at any dt: O(1) per event and
O(channels) per step. Online, :meth:`PSPFilterBank.step_events` takes the spikes as events
(step, channel) and writes the PSP only for the steps asked for: the states' decay is then
all the per-step work (two multiplications per channel), and the values are those of the
dense filter to the bit (the same operations in the same order).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral
from typing import ClassVar

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import Constraints, Interval, check_param, positive, validate_params


@dataclass(frozen=True)
class PSPParams:
    """Time constants of eq. 12 in milliseconds."""

    tau_d_ms: float = 4.0
    tau_r_ms: float = 12.5
    tau_m_ms: float = 21.3

    _parameter_constraints: ClassVar[Constraints] = {
        "tau_d_ms": positive("ms"),
        "tau_r_ms": positive("ms"),
        "tau_m_ms": positive("ms"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
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


@numba.njit(cache=True)
def _event_kernel(n_steps: int, steps: np.ndarray, addrs: np.ndarray, decay_d: float,
                  decay_r: float, scale: float, sd: np.ndarray, sr: np.ndarray,
                  out: np.ndarray, out_first: int, scratch: np.ndarray) -> None:  # pragma: no cover
    # steps (ascending, 0 <= s < n_steps) and addrs: the events; sd, sr: (n,) states, updated;
    # out: (m, n) PSP rows of steps out_first .. out_first + m - 1 (others not written);
    # scratch: (n,) zeros, left zero. Per channel and step: sd = decay_d * sd + c, as the
    # dense kernel (c = 0 adds nothing: x + 0.0 == x for the non-negative states)
    n = sd.shape[0]
    j = 0
    n_events = steps.shape[0]
    for k in range(n_steps):
        for i in range(n):
            sd[i] = decay_d * sd[i]
            sr[i] = decay_r * sr[i]
        j0 = j
        while j < n_events and steps[j] == k:
            scratch[addrs[j]] += 1.0
            j += 1
        for q in range(j0, j):
            a = addrs[q]
            c = scratch[a]
            if c != 0.0:  # the step's count of channel a, added once as the dense kernel does
                sd[a] += c
                sr[a] += c
                scratch[a] = 0.0
        r = k - out_first
        if 0 <= r < out.shape[0]:
            for i in range(n):
                out[r, i] = scale * (sd[i] - sr[i])


class PSPFilterBank:
    """Eq. 12 filter for ``n_channels`` channels at step ``dt_s`` (s); online and offline."""

    def __init__(self, n_channels: int, dt_s: float, params: PSPParams | None = None) -> None:
        check_param("dt_s", dt_s, positive("s"))
        check_param("n_channels", n_channels, Interval(Integral, 1, None, closed="left"))
        self.params = params or PSPParams()
        self.n_channels = int(n_channels)
        self.dt_s = float(dt_s)
        self.decay_d = math.exp(-dt_s * 1e3 / self.params.tau_d_ms)
        self.decay_r = math.exp(-dt_s * 1e3 / self.params.tau_r_ms)
        self._sd = np.zeros(self.n_channels)
        self._sr = np.zeros(self.n_channels)
        self._scratch = np.zeros(self.n_channels)

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

    def step_events(self, n_steps: int, steps: np.ndarray, channels: np.ndarray,
                    out: np.ndarray | None = None, out_first: int = 0) -> None:
        """Online, sparse: step the next ``n_steps`` steps with the spikes given as events
        (``steps``: each one's step relative to the first, ascending, 0 <= step <
        ``n_steps``; ``channels``: its channel) and keep state. ``out`` (m, n), when given,
        receives the PSP of the steps ``out_first`` .. ``out_first + m - 1`` (relative;
        rows outside the ``n_steps`` are left as they are). The values equal
        :meth:`step_block`'s on the same spikes, bit for bit."""
        st = np.ascontiguousarray(steps, dtype=np.int64)
        ch = np.ascontiguousarray(channels, dtype=np.int64)
        if st.shape != ch.shape or st.ndim != 1:
            raise ConfigError(f"steps {st.shape} and channels {ch.shape} must be equal 1-d")
        if st.size and (st[0] < 0 or st[-1] >= n_steps or np.any(np.diff(st) < 0)):
            raise ConfigError(f"event steps must be ascending within 0..{n_steps - 1}")
        if ch.size and (ch.min() < 0 or ch.max() >= self.n_channels):
            raise ConfigError(f"event channels must lie in 0..{self.n_channels - 1}")
        rows = np.empty((0, self.n_channels)) if out is None else out
        if rows.ndim != 2 or rows.shape[1] != self.n_channels or rows.dtype != np.float64:
            raise ConfigError(f"out has shape {rows.shape} and dtype {rows.dtype}; expected "
                              f"(m, {self.n_channels}) float64")
        _event_kernel(int(n_steps), st, ch, self.decay_d, self.decay_r, self.params.scale,
                      self._sd, self._sr, rows, int(out_first), self._scratch)

    def copy(self) -> PSPFilterBank:
        """An independent bank with this one's parameters and state."""
        twin = PSPFilterBank(self.n_channels, self.dt_s, self.params)
        twin._sd[:] = self._sd
        twin._sr[:] = self._sr
        return twin

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
