"""The reference receiver's decoders of the contact tasks (``protocols/SPEC.md`` §3.5.3): the
baseline a user's decoder is compared against. Each reads the spikes of one detected touch's
decision window (the onset rule of :mod:`skinhil.receiver.onset`, no ground truth):

- LOCALISATION (:func:`locate_mm`): the centroid of the sensors' rest positions (spring
  midpoints, :func:`skinhil.model.geometry.sensor_positions`) weighted by their spikes in the
  window;
- FORCE (:func:`force_n`): a line through the window's spike count, ``FORCE_OFFSET_N +
  FORCE_N_PER_SPIKE · spikes``, fitted by least squares on a calibration run
  (``benchmarks/fit_force_line.py``);
- VIBRATION (:func:`frequency_hz`): the frequency in :data:`VIBRATION_BAND_HZ` at which the
  spike times of the touch's first :data:`VIBRATION_WINDOW_S` on its most active channels
  phase-lock most (the peak of their Rayleigh periodogram, 1 Hz steps);
- SLIP (:func:`is_slip`): a second onset detected while the touch before it lasts
  (:data:`TOUCH_S`): the burst of a contact that starts to slide.
"""

from __future__ import annotations

import numpy as np

from skinhil.model.geometry import MeshSize, build_mesh, sensor_positions

SPACING_M = 1e-3
"""The skin's node spacing (m) the positions assume (:class:`skinhil.model.skin.SkinParams`)."""
FORCE_OFFSET_N = 0.5253
"""FORCE: the line's offset (N); with :data:`FORCE_N_PER_SPIKE`, the least-squares fit of
the normal force at the end of each detected touch's decision window on the window's spikes,
over the presses of ``examples/scenarios/task_force.toml`` simulated at the paper's 10 dB
with seed 1: ``python benchmarks/fit_force_line.py --snr-db 10 --seed 1`` (12 touches of 19
onsets, correlation −0.54, median |error| 0.086 N: the deeper presses give fewer spikes, the
springs under them compressed, and compression inhibits). Another SNR or skin needs its own
fit; the README's runs use another seed."""
FORCE_N_PER_SPIKE = -0.0028
"""FORCE: newtons per spike of the window (the fit above)."""
VIBRATION_BAND_HZ = (40.0, 500.0)
"""VIBRATION: the frequencies (Hz) searched."""
VIBRATION_WINDOW_S = 0.25
"""VIBRATION: the spikes of this long (s) from the touch's onset are read (the answer leaves
then, within the board's default 0.5 s response window)."""
VIBRATION_CHANNELS = 20
"""VIBRATION: only the spikes of the window's this many most active channels are read (the
touched sensors; the noise spreads over all of them)."""
TOUCH_S = 0.5
"""SLIP: an onset this soon (s) after the touch's onset belongs to that touch: a slip."""


def sensor_xy_mm(size: MeshSize) -> np.ndarray:
    """(n_channels, 2) rest positions (mm) of the sensors of a skin of top layer ``size``."""
    return sensor_positions(build_mesh(SPACING_M, SPACING_M, size))[:, :2] * 1e3


def locate_mm(addr: np.ndarray, xy_mm: np.ndarray) -> tuple[float, float]:
    """LOCALISATION: the spike-weighted centroid (mm) of the sensors ``addr`` spiked on; the
    skin's centre when none did."""
    if addr.shape[0] == 0:
        return 0.0, 0.0
    x, y = xy_mm[np.asarray(addr, dtype=np.int64)].mean(axis=0)
    return float(x), float(y)


def force_n(spikes: int) -> float:
    """FORCE: the normal force (N) the window's ``spikes`` stand for."""
    return max(FORCE_OFFSET_N + FORCE_N_PER_SPIKE * max(int(spikes), 0), 0.0)


def frequency_hz(t_us: np.ndarray, addr: np.ndarray | None = None) -> float:
    """VIBRATION: the frequency (Hz) at which spike times ``t_us`` (µs) lock in phase most,
    of the :data:`VIBRATION_CHANNELS` most active channels of ``addr`` when given; the
    band's low end when fewer than 3 spikes."""
    lo, hi = VIBRATION_BAND_HZ
    if addr is not None and t_us.shape[0]:
        counts = np.bincount(np.asarray(addr, dtype=np.int64))
        top = np.argsort(counts, kind="stable")[::-1][:VIBRATION_CHANNELS]
        t_us = t_us[np.isin(addr, top)]
    if t_us.shape[0] < 3:
        return lo
    t = (np.asarray(t_us, dtype=np.float64) - float(t_us[0])) * 1e-6
    f = np.arange(lo, hi + 1.0)
    phase = 2j * np.pi * f[:, None] * t[None, :]
    power = np.abs(np.exp(phase).sum(axis=1))
    return float(f[int(np.argmax(power))])


def is_slip(onset_us: int, touch_onset_us: int | None) -> bool:
    """SLIP: whether an onset at ``onset_us`` (µs) falls within the touch that began at
    ``touch_onset_us`` (µs; None: no touch yet)."""
    return touch_onset_us is not None and 0 < onset_us - touch_onset_us < TOUCH_S * 1e6
