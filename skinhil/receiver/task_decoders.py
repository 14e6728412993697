"""The reference receiver's decoders of the contact tasks (``protocols/SPEC.md`` §3.5.3): the
baseline a user's decoder is compared against. Each reads the spikes of one detected touch's
decision window (the onset rule of :mod:`skinhil.receiver.onset`, an onset called a
touch-down by :mod:`skinhil.receiver.touch_kind`; no ground truth):

- the touch's spikes (:func:`touch_spikes`): those of the window's first
  :data:`TOUCH_SPIKES_S` (the touch-down's burst; the noise, about 1 spike/s on each of the
  channels, spreads over the whole window and skin) lying within :data:`TOUCH_RADIUS_MM` of
  their trimmed centroid (the sensors' rest positions, spring midpoints,
  :func:`skinhil.model.geometry.sensor_positions`; from the median, moved
  :data:`TRIM_ROUNDS` times to the mean of the spikes within the radius);
- LOCALISATION: that trimmed centroid;
- FORCE (:func:`force_n`): a line through the count of the touch's spikes, ``FORCE_OFFSET_N +
  FORCE_N_PER_SPIKE · spikes``, fitted by least squares on calibration runs
  (``benchmarks/fit_force_line.py``);
- VIBRATION (:func:`frequency_hz`): the vibration class (Hz) whose calibrated mean is
  nearest the features of the touch's first :data:`VIBRATION_WINDOW_S` (:func:`vibration_features`:
  its spike count, and how much the spikes of its most active channels lock in phase to
  each class's frequency), in units of the features' within-class spread (a diagonal linear
  discriminant fitted on calibration runs: ``benchmarks/fit_vibration_classes.py``);
- SLIP (:func:`slip_time_us`): from :data:`SLIP_WATCH_S` after a touch's window start,
  the first time the last :data:`SLIP_WINDOW_S` hold :data:`SLIP_SPIKES` spikes of the
  :data:`SLIP_CHANNELS`, the channels that stay near silent while a held contact sticks and
  fire once it slides (fitted by ``benchmarks/fit_slip_channels.py``).

An onset within :data:`TOUCH_S` of a touch's (:func:`within_touch`) belongs to that touch
(its slide, its release) and is answered no further.
"""

from __future__ import annotations

import numpy as np

from skinhil.model.geometry import MeshSize, build_mesh, sensor_positions
from skinhil.receiver.reference_fit import reference_fit

SPACING_M = 1e-3
"""The skin's node spacing (m) the positions assume (:class:`skinhil.model.skin.SkinParams`)."""
TOUCH_SPIKES_S = 0.015
"""LOCALISATION, FORCE: the touch's spikes are read in this long (s) from the decision
window's start. With :data:`TOUCH_RADIUS_MM`, chosen among 10, 15, 20, 30 and 50 ms and 1,
1.5, 2 and 2.5 mm on the presses of ``examples/scenarios/task_localisation.toml`` simulated at
the paper's 10 dB with seeds 1-6 on the default skin, ``python benchmarks/fit_touch_spikes.py
--snr-db 10 --seeds 1,2,3,4,5,6`` (90 touches detected of 216, their onsets called
touch-downs by :mod:`skinhil.receiver.touch_kind`): 56 % of them located within 0.5 mm
(median 0.48 mm), against 27 % (0.81 mm) by the centroid of all the 50 ms window's
spikes."""
TOUCH_RADIUS_MM = 2.0
"""LOCALISATION, FORCE: the touch's spikes lie this near (mm) their trimmed centroid (chosen
with :data:`TOUCH_SPIKES_S`)."""
TRIM_ROUNDS = 3
"""LOCALISATION, FORCE: the trimmed centroid moves this many times to the mean of the spikes
within :data:`TOUCH_RADIUS_MM` of it."""
FIT = reference_fit()
"""The fitted parameters below and their provenance: ``skinhil/data/reference_fit.json``,
fitted on training seeds of the suite it names only (``python
benchmarks/fit_reference_answerers.py``), so no evaluation seed's trials were seen."""
FORCE_OFFSET_N: float = FIT["force"]["offset_n"]
"""FORCE: the line's offset (N); with :data:`FORCE_N_PER_SPIKE`, the least-squares fit of
the normal force at the end of each detected touch's decision window on the count of the
touch's spikes (:func:`touch_spikes`), over the presses of the suite's ``force`` case at the
fit's SNR on the default skin, their onsets called touch-downs
(:mod:`skinhil.receiver.touch_kind`): ``benchmarks/fit_force_line.py``. Another SNR or skin
needs its own fit."""
FORCE_N_PER_SPIKE: float = FIT["force"]["n_per_spike"]
"""FORCE: newtons per spike of the touch (the fit above)."""
VIBRATION_BAND_HZ = (40.0, 500.0)
"""VIBRATION: the band (Hz) of the frequencies asked (the random answerer draws from it)."""
VIBRATION_WINDOW_S = 0.3
"""VIBRATION: the spikes of this long (s) from the touch's decision window's start are read
(the answer leaves then, within the board's default 0.5 s response window)."""
VIBRATION_CHANNELS = 20
"""VIBRATION: the phase locking is read on the window's this many most active channels (the
touched sensors; the noise spreads over all of them)."""
VIBRATION_CLASSES_HZ = (50.0, 100.0, 200.0, 300.0)
"""VIBRATION: the frequencies (Hz) of the calibration case (the suite's ``vibration``), the
answers the decoder gives."""
VIBRATION_MEANS: tuple[tuple[float, ...], ...] = tuple(
    tuple(row) for row in FIT["vibration"]["means"])
"""VIBRATION: per class of :data:`VIBRATION_CLASSES_HZ`, the mean of
:func:`vibration_features` over the calibration touches of the suite's ``vibration`` case,
their onsets called touch-downs (:mod:`skinhil.receiver.touch_kind`):
``benchmarks/fit_vibration_classes.py``. Another SNR, skin or set of frequencies needs its
own fit."""
VIBRATION_SPREAD: tuple[float, ...] = tuple(FIT["vibration"]["spread"])
"""VIBRATION: the within-class standard deviation of each feature (the fit above)."""
TOUCH_S = 0.5
"""An onset this soon (s) after a touch's onset belongs to that touch."""
SLIP_CHANNELS: tuple[int, ...] = tuple(FIT["slip"]["channels"])
"""SLIP: the channels near silent while a held contact sticks (at most 0.5 spikes in 70 ms)
that fire at least 0.5 spikes more in the 70 ms after it slips, on average over the slides
of the suite's ``slip`` case: ``benchmarks/fit_slip_channels.py``. Another SNR, skin, place
or direction of slip needs its own fit."""
SLIP_WINDOW_S = 0.15
"""SLIP: the spikes of the slip channels are counted over this long (s)."""
SLIP_SPIKES = 10
"""SLIP: this many spikes of the slip channels within :data:`SLIP_WINDOW_S` are a slip
(with :data:`SLIP_WINDOW_S` chosen on seeds 5 and 6 of the scenario: 9 of 12 slips each)."""
SLIP_WATCH_S = (0.1, 0.6)
"""SLIP: a touch is watched from this long (s) after its window start (past its touch-down's
own burst) until this long."""


def sensor_xy_mm(size: MeshSize) -> np.ndarray:
    """(n_channels, 2) rest positions (mm) of the sensors of a skin of top layer ``size``."""
    return sensor_positions(build_mesh(SPACING_M, SPACING_M, size))[:, :2] * 1e3


def touch_spikes(t_us: np.ndarray, addr: np.ndarray, start_us: int, xy_mm: np.ndarray,
                 spikes_s: float = TOUCH_SPIKES_S,
                 radius_mm: float = TOUCH_RADIUS_MM) -> tuple[tuple[float, float], int]:
    """The touch's spikes among a window's (times ``t_us`` µs, channels ``addr``; sensors at
    ``xy_mm``, mm) from ``start_us`` (µs), those of its first ``spikes_s`` (s) within
    ``radius_mm`` (mm) of their trimmed centroid: that centroid (mm; the skin's centre when
    none) and their count."""
    addr = np.asarray(addr, dtype=np.int64)
    t = np.asarray(t_us, dtype=np.int64)
    keep = (t >= start_us) & (t < start_us + int(spikes_s * 1e6)) & (addr < len(xy_mm))
    p = xy_mm[addr[keep]]
    if p.shape[0] == 0:
        return (0.0, 0.0), 0
    centre = np.median(p, axis=0)
    for _ in range(TRIM_ROUNDS):
        near = np.hypot(*(p - centre).T) <= radius_mm
        if not near.any():
            break
        centre = p[near].mean(axis=0)
    near = np.hypot(*(p - centre).T) <= radius_mm
    return (float(centre[0]), float(centre[1])), int(near.sum())


def force_n(spikes: int) -> float:
    """FORCE: the normal force (N) a touch of ``spikes`` spikes (:func:`touch_spikes`)
    stands for."""
    return max(FORCE_OFFSET_N + FORCE_N_PER_SPIKE * max(int(spikes), 0), 0.0)


def vibration_features(t_us: np.ndarray, addr: np.ndarray) -> np.ndarray:
    """VIBRATION: the features of a window's spikes (times ``t_us`` µs, channels ``addr``):
    its spike count, then for each frequency ``f`` of :data:`VIBRATION_CLASSES_HZ` the
    Rayleigh power ``|Σ exp(2πi f t)|² / n`` of the spikes of its
    :data:`VIBRATION_CHANNELS` most active channels (1 for unlocked spikes, n for perfect
    locking)."""
    addr = np.asarray(addr, dtype=np.int64)
    t = np.asarray(t_us, dtype=np.float64) * 1e-6
    if addr.shape[0]:
        top = np.argsort(np.bincount(addr), kind="stable")[::-1][:VIBRATION_CHANNELS]
        t = t[np.isin(addr, top)]
    f = np.asarray(VIBRATION_CLASSES_HZ)
    power = np.abs(np.exp(2j * np.pi * f[:, None] * t[None, :]).sum(axis=1)) ** 2
    return np.concatenate([[float(addr.shape[0])], power / max(t.shape[0], 1)])


def vibration_class_hz(features: np.ndarray) -> float:
    """VIBRATION: the class (Hz, one of :data:`VIBRATION_CLASSES_HZ`) whose mean
    :data:`VIBRATION_MEANS` is nearest ``features`` (:func:`vibration_features`), each feature
    in units of its spread :data:`VIBRATION_SPREAD`."""
    z = (np.asarray(features) - np.asarray(VIBRATION_MEANS)) / np.asarray(VIBRATION_SPREAD)
    return VIBRATION_CLASSES_HZ[int(np.argmin((z ** 2).sum(axis=1)))]


def frequency_hz(t_us: np.ndarray, addr: np.ndarray) -> float:
    """VIBRATION: the class (Hz) of a window's spikes (times ``t_us`` µs, channels
    ``addr``): :func:`vibration_class_hz` of their :func:`vibration_features`."""
    return vibration_class_hz(vibration_features(t_us, addr))


def within_touch(onset_us: int, touch_onset_us: int | None) -> bool:
    """Whether an onset at ``onset_us`` (µs) falls within the touch that began at
    ``touch_onset_us`` (µs; None: no touch yet)."""
    return touch_onset_us is not None and 0 < onset_us - touch_onset_us < TOUCH_S * 1e6


def slip_time_us(t_us: np.ndarray, addr: np.ndarray, start_us: int) -> int | None:
    """SLIP: the board time (µs) of the first spike, :data:`SLIP_WATCH_S` after a touch's
    window start ``start_us`` (µs), at which the last :data:`SLIP_WINDOW_S` hold
    :data:`SLIP_SPIKES` spikes of the :data:`SLIP_CHANNELS` among spikes ``t_us`` (µs, in
    time order), ``addr``; None when none (yet)."""
    lo, hi = (start_us + int(s * 1e6) for s in SLIP_WATCH_S)
    t = np.asarray(t_us, dtype=np.int64)
    t = t[np.isin(addr, SLIP_CHANNELS) & (t >= lo) & (t < hi)]
    if t.shape[0] < SLIP_SPIKES:
        return None
    span = t[SLIP_SPIKES - 1:] - t[:t.shape[0] - SLIP_SPIKES + 1]
    hit = np.flatnonzero(span < int(SLIP_WINDOW_S * 1e6))
    return int(t[hit[0] + SLIP_SPIKES - 1]) if hit.shape[0] else None
