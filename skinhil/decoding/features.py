"""Decoder features: time-binned PSP-filtered activity of the sensors after a stimulus onset.

Definition (one place, shared by offline training and the online receiver):

- The spike raster (steps of ``dt_s`` s, one column per sensor channel) is filtered by the
  paper's PSP kernel (eq. 12, :class:`skinhil.PSPFilterBank` with ``spec.psp``), from rest.
- The **window** is the first ``n_steps = round(window_s / dt_s)`` steps from the onset
  (row 0 of the trace is the onset step). It is cut into ``n_bins = n_steps // bin_steps``
  consecutive bins of ``bin_steps = round(bin_s / dt_s)`` steps.
- A **feature** is the mean PSP value (unitless, eq. 12 scale: one isolated spike peaks at
  ≈1.0) of one selected channel over one bin. Features are ordered bin-major:
  ``index = bin · n_selected + k`` for the k-th selected channel.
- **Channels**: all ``n_channels`` sensors (338 springs, spring order of
  :attr:`skinhil.SkinModel.springs`) by default, or the sorted 0-based subset ``channels``.

Defaults: ``window_s = 0.05`` s in ``bin_s = 0.01`` s bins: with the default skin the evoked
spikes of the Figure 4 conditions come within the first ~20 ms after onset, and a 50 ms
window keeps the online decision latency short; 5 bins x 338 channels = 1690 features.

The same :meth:`FeatureSpec.transform` takes a PSP trace computed offline by
:meth:`PSPFilterBank.filter` or online, step by step, by :meth:`PSPFilterBank.step`: both give
the same numbers, so a decoder trained offline sees the same features online.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from numbers import Integral
from typing import Any, ClassVar

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.psp import PSPFilterBank, PSPParams
from skinhil.validation import Constraints, InstanceOf, Interval, positive, validate_params

DEFAULT_N_CHANNELS = 338
"""Sensor count of the paper's skin (one per spring)."""


def _steps(duration_s: float, dt_s: float, name: str) -> int:
    n = int(round(duration_s / dt_s))
    if n < 1 or abs(n * dt_s - duration_s) > 1e-9 * max(1.0, duration_s) + 1e-12:
        raise ConfigError(f"FeatureSpec.{name}={duration_s!r} s is not a positive whole number "
                          f"of steps of dt_s={dt_s!r} s; choose a multiple of dt_s")
    return n


@dataclass(frozen=True)
class FeatureSpec:
    """What a feature vector is (see the module docstring); units in the names.

    ``dt_s`` (s) is the simulation/board step the raster and PSP trace are sampled at,
    ``window_s`` (s) the window length from the onset, ``bin_s`` (s) the bin width,
    ``channels`` the 0-based selected channels (``None``: all), ``n_channels`` the channel
    count of the stream, ``psp`` the PSP kernel's time constants.
    """

    dt_s: float = 1e-4
    window_s: float = 0.05
    bin_s: float = 0.01
    channels: tuple[int, ...] | None = None
    n_channels: int = DEFAULT_N_CHANNELS
    psp: PSPParams = PSPParams()

    _parameter_constraints: ClassVar[Constraints] = {
        "dt_s": positive("s"),
        "window_s": positive("s"),
        "bin_s": positive("s"),
        "n_channels": Interval(Integral, 1, None, closed="left", unit="channels"),
        "psp": InstanceOf(PSPParams, "a skinhil.PSPParams"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
        n_steps = _steps(self.window_s, self.dt_s, "window_s")
        bin_steps = _steps(self.bin_s, self.dt_s, "bin_s")
        if n_steps % bin_steps:
            raise ConfigError(f"FeatureSpec: window_s={self.window_s!r} s is not a whole number "
                              f"of bins of bin_s={self.bin_s!r} s; choose bins that tile it")
        if self.channels is not None:
            chans = tuple(int(c) for c in self.channels)
            if not chans or list(chans) != sorted(set(chans)) or chans[0] < 0 \
                    or chans[-1] >= self.n_channels:
                raise ConfigError(f"FeatureSpec.channels must be sorted distinct indices in "
                                  f"0..{self.n_channels - 1}, got {self.channels!r}")
            object.__setattr__(self, "channels", chans)

    @property
    def n_steps(self) -> int:
        """Window length in steps of ``dt_s``."""
        return int(round(self.window_s / self.dt_s))

    @property
    def bin_steps(self) -> int:
        """Bin width in steps of ``dt_s``."""
        return int(round(self.bin_s / self.dt_s))

    @property
    def n_bins(self) -> int:
        """Number of time bins in the window."""
        return self.n_steps // self.bin_steps

    @property
    def channel_index(self) -> np.ndarray:
        """0-based indices of the selected channels (int64)."""
        if self.channels is None:
            return np.arange(self.n_channels)
        return np.asarray(self.channels, dtype=np.int64)

    @property
    def n_features(self) -> int:
        """Length of one feature vector: ``n_bins`` x selected channels."""
        return self.n_bins * (self.n_channels if self.channels is None else len(self.channels))

    def transform(self, psp: np.ndarray) -> np.ndarray:
        """PSP traces (..., n, n_channels) starting at the onset → features (..., n_features).

        Only the first ``n_steps`` rows are used; ``n`` must be at least ``n_steps``.
        """
        x = np.asarray(psp)
        if x.ndim < 2 or x.shape[-1] != self.n_channels:
            raise ConfigError(f"PSP trace has shape {x.shape}; expected (..., n_steps, "
                              f"{self.n_channels}) for this feature spec")
        if x.shape[-2] < self.n_steps:
            raise ConfigError(f"PSP trace has {x.shape[-2]} steps but the feature window needs "
                              f"{self.n_steps} ({self.window_s:g} s at dt {self.dt_s:g} s)")
        lead = x.shape[:-2]
        win = x[..., : self.n_steps, :]
        if self.channels is not None:
            win = win[..., self.channel_index]
        binned = win.reshape(*lead, self.n_bins, self.bin_steps, win.shape[-1]).mean(axis=-2)
        return np.asarray(binned.reshape(*lead, self.n_features), dtype=np.float64)

    def raster_features(self, raster: np.ndarray, chunk_trials: int = 32) -> np.ndarray:
        """Spike raster (..., n, n_channels) from rest, onset at row 0 → (..., n_features).

        PSP-filters with :class:`PSPFilterBank` then applies :meth:`transform`; works through
        the leading trials ``chunk_trials`` at a time to bound memory.
        """
        r = np.asarray(raster)
        if r.ndim < 2:
            raise ConfigError(f"raster has shape {r.shape}; expected (..., n_steps, channels)")
        lead = r.shape[:-2]
        flat = r.reshape(-1, *r.shape[-2:])[:, : self.n_steps]
        bank = PSPFilterBank(self.n_channels, self.dt_s, self.psp)
        out = np.empty((flat.shape[0], self.n_features))
        for start in range(0, flat.shape[0], max(1, chunk_trials)):
            block = flat[start:start + chunk_trials]
            if block.shape[-1] != self.n_channels:
                raise ConfigError(f"raster has {block.shape[-1]} channels; the feature spec "
                                  f"expects {self.n_channels}")
            out[start:start + block.shape[0]] = self.transform(bank.filter(block))
        return out.reshape(*lead, self.n_features)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able form (see :meth:`from_dict`)."""
        d = asdict(self)
        d["channels"] = None if self.channels is None else list(self.channels)
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FeatureSpec:
        """Inverse of :meth:`to_dict`; raises ConfigError on unknown or missing keys."""
        known = {"dt_s", "window_s", "bin_s", "channels", "n_channels", "psp"}
        if not isinstance(data, Mapping) or set(data) != known:
            got = sorted(data) if isinstance(data, Mapping) else type(data).__name__
            raise ConfigError(f"feature spec needs exactly the keys {sorted(known)}, got {got}")
        psp = data["psp"]
        if not isinstance(psp, Mapping):
            raise ConfigError("feature spec: 'psp' must be a table of tau_d_ms, tau_r_ms, "
                              "tau_m_ms")
        try:
            psp_params = PSPParams(**{k: float(v) for k, v in psp.items()})
        except TypeError as exc:
            raise ConfigError(f"feature spec: bad 'psp' entry: {exc}") from None
        chans = data["channels"]
        return cls(dt_s=float(data["dt_s"]), window_s=float(data["window_s"]),
                   bin_s=float(data["bin_s"]),
                   channels=None if chans is None else tuple(int(c) for c in chans),
                   n_channels=int(data["n_channels"]), psp=psp_params)
