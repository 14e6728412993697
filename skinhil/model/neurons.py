"""Noisy Izhikevich neurons, one per spring, vectorised over channels and trials.

Model (Izhikevich 2003; time in ms, v and u in mV, as in the paper)::

    v' = 0.04 v² + 5 v + 140 − u + K·I
    u' = a (b v − u)
    if v ≥ 30 mV: spike, v ← c, u ← u + d

with a = 0.02, b = 0.2, c = −65 mV, d = 9, K = 500 and I the spring's force in newtons,
signed: tension (I > 0) excites, compression (I < 0) inhibits. Initial state v = c, u = b·c.

Noise: white Gaussian noise on v and on u, as a diffusion with a reference step so that its
statistics do not depend on dt (Euler–Maruyama). Every step of dt (ms) adds
``σ·sqrt(dt/dt_ref)·N(0,1)`` (mV) to v and, independently, to u, with

    σ² = P_ref · 10^(−snr_db/10),   P_ref = 1 mV²,   dt_ref = 1 ms    (:class:`NoiseParams`).

P_ref = 1 mV² is MATLAB ``awgn(x, snr)``'s default signal power (0 dBW): at the paper's 10 dB,
σ ≈ 0.32 mV per millisecond. dt_ref = 1 ms is the Izhikevich model's canonical step (the
model's constants are fitted for time in ms and Izhikevich 2003 integrates it at 1 ms), so at
dt = 1 ms the noise is exactly ``awgn`` applied once per step; at a finer step the variance
per unit time is the same, so spike counts and ISI statistics do not move with dt.
``snr_db = inf`` adds nothing and the model is deterministic.

Option ``NoiseParams(definition="measured")`` (never the default) is MATLAB's ``awgn(x,
snr, 'measured')`` applied at every step whatever dt: ``σ² = mean(x²) · 10^(−snr_db/10)``
over the population vector ``x`` (the values of v, or of u, of one trial) at that step.
Because σ is measured from the state it is added to, the noise on u feeds itself: u relaxes
by ``(1 − a·dt)`` per step, so its mean square grows without bound when ``10^(−SNR/10) > 1
− (1 − a·dt)²``, below about 24 dB at dt = 0.1 ms (14 dB at 1 ms). Left alone it overflows
to NaN and the population falls silent for good, so under this option, before the noise of
a step, a trial whose population RMS of u exceeds ``BLOWUP_RMS_MV`` (10⁴ mV, a thousand
times any physiological value) or whose v is not finite is put back at rest (v = c, u =
b·c) and counted in ``NeuronPopulation.blowups``.
The diffusion noise has a fixed σ and needs no such guard.

The per-step order, for every step k of length dt (ms), each trial independently:

1. Euler: ``v ← v + dt·(0.04v² + 5v + 140 − u + K·I[k])``, ``u ← u + dt·a·(b·v_old − u)``;
2. noise: ``v ← v + σ_v·N(0,1)``, ``u ← u + σ_u·N(0,1)``, with ``σ_v = σ_u = σ·sqrt(dt/dt_ref)``
   (under ``"measured"``: σ_v, σ_u measured from the updated v, u after the run-away guard);
3. threshold: where ``v ≥ 30``: a spike in step k, ``v ← c``, ``u ← u + d``.

A spike in step k is stamped with the step's start time ``k·dt`` (see
:func:`raster_to_events`). Noise comes from :mod:`skinhil.model.rng`: the two normals of
channel i at the population's step number k (counted from its creation, across calls) are a
function of the channel's key (one per channel and trial, from the seed) and k alone, so any
split of the work, on any number of threads, draws the same numbers.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import ClassVar, Literal, NamedTuple

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.events import EVENT_DTYPE, make_events
from skinhil.model.normals import normals_ext
from skinhil.model.rng import seed_keys
from skinhil.validation import (
    Constraints,
    StrOptions,
    check_param,
    finite,
    positive,
    validate_params,
)


class NeuronOperands(NamedTuple):
    """What the compiled neuron step reads (:meth:`NeuronPopulation.kernel_operands`): the
    membranes and the noise streams, updated in place, and the parameters."""

    v: np.ndarray
    """Membrane potentials (batch, n) mV."""
    u: np.ndarray
    """Recovery variables (batch, n)."""
    a: float
    b: float
    c: float
    """Reset potential (mV)."""
    d: float
    gain: float
    """K (mV/ms per newton)."""
    v_peak: float
    """Spike threshold (mV)."""
    measured: bool
    """Whether the noise is the measured-power one."""
    noise_var: float
    """:meth:`NoiseParams.variance` at the SNR."""
    ref_step_ms: float
    """The diffusion's reference step (ms)."""
    keys: np.ndarray
    """Noise keys (batch, n) uint64."""
    clock: np.ndarray
    """Steps made (1,) int64: where the noise streams are."""
    blowups: np.ndarray
    """Per trial, the measured-power noise's run-aways (batch,) int64."""


CHANNEL_BLOCK = 1024
"""Channels the kernels update together (while their state is in cache), and the unit of work
shared among threads; the draws do not depend on it (each channel has its own key)."""

BLOWUP_RMS_MV = 1e4
"""Population RMS of u (mV) beyond which a trial counts as run away under the measured-power
noise (see module docstring)."""

NoiseDefinition = Literal["diffusion", "measured"]


@dataclass(frozen=True)
class NoiseParams:
    """How an SNR becomes neuron noise (module docstring): ``"diffusion"`` (default) adds
    ``σ·sqrt(dt/ref_step_ms)·N(0,1)`` mV per step with ``σ² = ref_power_mv2·10^(−SNR/10)``;
    ``"measured"`` is ``awgn(x, snr, 'measured')`` at every step (runs away below ~24 dB at
    0.1 ms; ``ref_power_mv2`` and ``ref_step_ms`` are then unused)."""

    definition: NoiseDefinition = "diffusion"
    ref_power_mv2: float = 1.0
    """Signal power P_ref (mV²) the SNR refers to: 1 mV² is MATLAB ``awgn``'s 0 dBW."""
    ref_step_ms: float = 1.0
    """Step (ms) at which σ is the whole per-step noise: the Izhikevich model's 1 ms step."""

    _parameter_constraints: ClassVar[Constraints] = {
        "definition": StrOptions(("diffusion", "measured")),
        "ref_power_mv2": positive("mV²"),
        "ref_step_ms": positive("ms"),
    }

    def __post_init__(self) -> None:
        validate_params(self)

    def variance(self, snr_db: float) -> float:
        """What the kernel scales its normals by at ``snr_db`` (0 for inf): σ² (mV² per
        reference step) for the diffusion, the power ratio ``10^(−SNR/10)`` if measured."""
        ratio = noise_power_ratio(snr_db)
        return ratio if self.definition == "measured" else self.ref_power_mv2 * ratio

    def sigma_per_step_mv(self, snr_db: float, dt_s: float) -> float:
        """Diffusion noise σ added per step of ``dt_s`` (s), in mV: ``σ·sqrt(dt/dt_ref)``."""
        if self.definition == "measured":
            raise ConfigError("the measured-power noise has no fixed σ per step: it is "
                              "measured from the state at every step")
        return math.sqrt(self.variance(snr_db) * dt_s * 1e3 / self.ref_step_ms)


@dataclass(frozen=True)
class IzhikevichParams:
    """Izhikevich parameters (paper values); ``gain`` is K, in mV/ms per newton."""

    a: float = 0.02
    b: float = 0.2
    c_mv: float = -65.0
    d: float = 9.0
    gain: float = 500.0
    v_peak_mv: float = 30.0

    _parameter_constraints: ClassVar[Constraints] = {
        "a": finite("1/ms"),
        "b": finite(),
        "c_mv": finite("mV"),
        "d": finite("mV"),
        "gain": finite("mV/ms per N"),
        "v_peak_mv": finite("mV"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
        if self.c_mv >= self.v_peak_mv:
            raise ConfigError("IzhikevichParams: reset c_mv must lie below the spike peak "
                              f"v_peak_mv ({self.c_mv} >= {self.v_peak_mv})")


MIN_SNR_DB = -20.0
"""Lowest SNR (dB) a neuron noise takes: σ = 10 mV per √ms (P_ref 1 mV²), every neuron near
its highest rate already. Below it the noise only grows numbers (at −1000 dB σ = 1e50 mV),
never information."""
MAX_SNR_DB = 200.0
"""Highest finite SNR (dB): σ = 1e-10 mV per √ms, no spike moved; give inf for no noise."""


def check_snr_db(snr_db: float) -> float:
    """Validate an SNR in dB (:data:`MIN_SNR_DB` .. :data:`MAX_SNR_DB`, or +inf for no noise)
    and return it as float."""
    try:
        value = float(snr_db)
    except (TypeError, ValueError):
        raise ConfigError(f"snr_db must be a number of dB or inf, got {snr_db!r}") from None
    if value != math.inf and not MIN_SNR_DB <= value <= MAX_SNR_DB:
        raise ConfigError(f"SNR {snr_db!r} dB is outside {MIN_SNR_DB:g}..{MAX_SNR_DB:g} dB: "
                          "give a value in that range, or inf for no noise")
    return value


def noise_power_ratio(snr_db: float) -> float:
    """``10^(−snr_db/10)``: noise variance per unit of measured signal power (0 for inf)."""
    value = check_snr_db(snr_db)
    return 0.0 if value == math.inf else 10.0 ** (-value / 10.0)


@numba.njit(inline="always")
def _euler(vv: float, uu: float, current: float, dt_ms: float, a: float, b: float,
           gain: float) -> tuple[float, float]:  # pragma: no cover - compiled
    # step 1 for one neuron: v (mV), u and its current (N) after dt_ms (ms)
    return (vv + dt_ms * (0.04 * vv * vv + 5.0 * vv + 140.0 - uu + gain * current),
            uu + dt_ms * a * (b * vv - uu))


@numba.njit(inline="always")
def _noise_then_threshold(vv: float, uu: float, zv: float, zu: float, sv: float, su: float,
                          c: float, d: float,
                          v_peak: float) -> tuple[bool, float, float]:  # pragma: no cover
    # steps 2 and 3 for one neuron: add σ·N(0,1) (mV), then spike and reset where v ≥ v_peak
    # (branch-free: a spike's branch would be mispredicted at noisy rates); (fired, v, u)
    vv = vv + sv * zv
    uu = uu + su * zu
    fired = vv >= v_peak
    return fired, c if fired else vv, uu + d if fired else uu


@numba.njit(inline="always")
def _euler_step(v: np.ndarray, u: np.ndarray, current: np.ndarray, dt_ms: float, a: float,
                b: float, gain: float) -> None:  # pragma: no cover - compiled
    # step 1 for one trial's row: v (mV), u, current (N) over dt_ms (ms), in place
    for i in range(v.shape[0]):
        v[i], u[i] = _euler(v[i], u[i], current[i], dt_ms, a, b, gain)


@numba.njit(inline="always")
def _power(v: np.ndarray, u: np.ndarray) -> tuple[float, float]:  # pragma: no cover
    # Σ v² and Σ u² (mV²) over the row, summed in channel order
    pv = 0.0
    pu = 0.0
    for i in range(v.shape[0]):
        pv += v[i] * v[i]
        pu += u[i] * u[i]
    return pv, pu


@numba.njit(inline="always")
def _noise_and_threshold(v: np.ndarray, u: np.ndarray, zv: np.ndarray, zu: np.ndarray,
                         sv: float, su: float, c: float, d: float, v_peak: float,
                         spikes: np.ndarray) -> None:  # pragma: no cover - compiled
    # steps 2 and 3 for one row, the normals in zv, zu
    for i in range(v.shape[0]):
        spikes[i], v[i], u[i] = _noise_then_threshold(v[i], u[i], zv[i], zu[i], sv, su, c, d,
                                                      v_peak)


@numba.njit(inline="always")
def _diffusion_block(v: np.ndarray, u: np.ndarray, current: np.ndarray, keys: np.ndarray,
                     step: int, sigma: float, dt_ms: float, a: float, b: float, c: float,
                     d: float, gain: float, v_peak: float, spikes: np.ndarray,
                     zv: np.ndarray, zu: np.ndarray) -> None:  # pragma: no cover - compiled
    # steps 1-3 at step number ``step`` for one block of channels under the diffusion noise:
    # the C kernel fills the block's normals into the float32 scratch zv, zu (one call),
    # then one branch-free pass does Euler, noise and threshold (it vectorises)
    n = v.shape[0]
    if sigma == 0.0:
        for i in range(n):
            vv, uu = _euler(v[i], u[i], current[i], dt_ms, a, b, gain)
            spikes[i], v[i], u[i] = _noise_then_threshold(vv, uu, 0.0, 0.0, 0.0, 0.0, c, d,
                                                          v_peak)
        return
    normals_ext(keys.ctypes, n, step, zv.ctypes, zu.ctypes)
    for i in range(n):
        vv, uu = _euler(v[i], u[i], current[i], dt_ms, a, b, gain)
        spikes[i], v[i], u[i] = _noise_then_threshold(vv, uu, np.float64(zv[i]),
                                                      np.float64(zu[i]), sigma, sigma, c, d,
                                                      v_peak)


@numba.njit(cache=True, fastmath=False, nogil=True)
def _izhikevich_kernel(current: np.ndarray, dt_ms: float, spikes: np.ndarray,
                       neurons: tuple) -> None:  # pragma: no cover - compiled
    # current (n_steps, 1 or n_batch, n) N over steps of dt_ms (ms) → spikes (n_steps,
    # n_batch, n); neurons is NeuronPopulation.kernel_operands() as a plain tuple
    p = NeuronOperands(*neurons)
    v, u, keys, c, d = p.v, p.u, p.keys, p.c, p.d
    n_steps, n_batch, n = spikes.shape
    shared_input = current.shape[1] == 1
    sigma_step = math.sqrt(p.noise_var * dt_ms / p.ref_step_ms)  # diffusion σ per step (mV)
    first = p.clock[0]
    p.clock[0] += n_steps
    zv = np.zeros(n, np.float32)  # a step's normals (C kernel), drawn before use
    zu = np.zeros(n, np.float32)
    if not p.measured:  # block by block: each block's state used while in cache
        for k in range(n_steps):
            for bb in range(n_batch):
                cur = current[k, 0 if shared_input else bb]
                for lo in range(0, n, CHANNEL_BLOCK):
                    hi = min(n, lo + CHANNEL_BLOCK)
                    _diffusion_block(v[bb, lo:hi], u[bb, lo:hi], cur[lo:hi], keys[bb, lo:hi],
                                     first + k, sigma_step, dt_ms, p.a, p.b, c, d, p.gain,
                                     p.v_peak, spikes[k, bb, lo:hi], zv[lo:hi], zu[lo:hi])
        return
    for k in range(n_steps):
        for bb in range(n_batch):
            vb = v[bb]
            ub = u[bb]
            _euler_step(vb, ub, current[k, 0 if shared_input else bb], dt_ms, p.a, p.b, p.gain)
            pv, pu = _power(vb, ub)
            if not (pu <= n * BLOWUP_RMS_MV * BLOWUP_RMS_MV and pv < math.inf):
                # the measured-power noise has run away: this trial starts again at rest
                p.blowups[bb] += 1
                vb[:] = c
                ub[:] = p.b * c
                pv = n * c * c
                pu = n * (p.b * c) * (p.b * c)
            sv = math.sqrt(pv / n * p.noise_var)
            su = math.sqrt(pu / n * p.noise_var)
            if p.noise_var > 0.0:
                normals_ext(keys[bb].ctypes, n, first + k, zv.ctypes, zu.ctypes)
            _noise_and_threshold(vb, ub, zv, zu, sv, su, c, d, p.v_peak, spikes[k, bb])


@numba.njit(cache=True, fastmath=False, parallel=True, nogil=True)
def _izhikevich_parallel_kernel(current: np.ndarray, dt_ms: float, spikes: np.ndarray,
                                neurons: tuple) -> None:  # pragma: no cover - compiled
    # _izhikevich_kernel for the diffusion noise (measured is False), the channel blocks of
    # every trial shared among numba's threads: the same arithmetic and draws per channel,
    # so the same spikes; blowups stays untouched (the diffusion never runs away)
    p = NeuronOperands(*neurons)
    v, u, keys = p.v, p.u, p.keys
    a, b, c, d, gain, v_peak = p.a, p.b, p.c, p.d, p.gain, p.v_peak
    n_steps, n_batch, n = spikes.shape
    n_blocks = -(-n // CHANNEL_BLOCK)
    shared_input = current.shape[1] == 1
    sigma_step = math.sqrt(p.noise_var * dt_ms / p.ref_step_ms)
    first = p.clock[0]
    for job in numba.prange(n_batch * n_blocks):
        bb = job // n_blocks
        lo = (job % n_blocks) * CHANNEL_BLOCK
        hi = min(n, lo + CHANNEL_BLOCK)
        zv = np.empty(hi - lo, np.float32)  # this job's normals (C kernel)
        zu = np.empty(hi - lo, np.float32)
        for k in range(n_steps):
            _diffusion_block(v[bb, lo:hi], u[bb, lo:hi],
                             current[k, 0 if shared_input else bb, lo:hi], keys[bb, lo:hi],
                             first + k, sigma_step, dt_ms, a, b, c, d, gain, v_peak,
                             spikes[k, bb, lo:hi], zv, zu)
    p.clock[0] += n_steps


@numba.njit(cache=True, nogil=True)
def fire(springs: np.ndarray, dt_s: float, spikes: np.ndarray,
         neurons: tuple) -> None:  # pragma: no cover - compiled
    """One trial's neurons over a block: spring forces (n_steps, n) N, each held over a step
    of ``dt_s`` (s) → bool ``spikes`` (n_steps, n); ``neurons`` is
    :meth:`NeuronPopulation.kernel_operands` as a plain tuple (the sensor kernels' last
    piece)."""
    n_steps, n = springs.shape
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt_s * 1e3,
                       spikes.reshape(n_steps, 1, n), neurons)


def check_threads(threads: int) -> int:
    """Validate a thread count for the compiled kernels (1 .. numba's thread count, the
    machine's cores unless NUMBA_NUM_THREADS says otherwise) and return it."""
    limit = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    if not (isinstance(threads, int | np.integer) and 1 <= threads <= limit):
        raise ConfigError(f"threads must be a whole number from 1 to {limit} (the cores numba "
                          f"may use; set NUMBA_NUM_THREADS for more), got {threads!r}")
    if threads > 1:
        # OpenMP threads that spin between parallel regions (one per block) take the cores
        # from everything else, on a busy machine many times the work itself
        # (benchmarks/bench_size.py --threads 2 measures the neurons). Read when the
        # OpenMP runtime starts, i.e. at the first parallel block, unless already set.
        os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    return int(threads)


class NeuronPopulation:
    """A population of ``n_channels`` noisy Izhikevich neurons, optionally ``batch`` trials.

    ``seed`` makes the noise reproducible (each channel of each trial has its own key, and
    its normals at step k are a function of the key and k alone: :mod:`skinhil.model.rng`);
    ``noise`` says how ``snr_db``
    becomes noise (default: the step-invariant diffusion). ``threads`` > 1 shares the
    channel blocks of every trial among that many threads (diffusion noise only): the same
    spikes as one thread, in less time once there are a few thousand channels.
    """

    def __init__(self, n_channels: int, params: IzhikevichParams | None = None,
                 snr_db: float = math.inf, seed: int | np.random.SeedSequence | None = None,
                 batch: int | None = None, noise: NoiseParams | None = None,
                 threads: int = 1) -> None:
        if not (isinstance(n_channels, int | np.integer) and n_channels > 0):
            raise ConfigError(f"n_channels must be a positive integer, got {n_channels!r}")
        if batch is not None and not (isinstance(batch, int | np.integer) and batch > 0):
            raise ConfigError(f"batch must be a positive integer or None, got {batch!r}")
        self.params = params or IzhikevichParams()
        self.n_channels = int(n_channels)
        self.batch = batch
        self._n_batch = 1 if batch is None else int(batch)
        self.noise = noise or NoiseParams()
        self.snr_db = check_snr_db(snr_db)
        self._noise_var = self.noise.variance(snr_db)
        self.threads = check_threads(threads)
        if self.threads > 1 and self.noise.definition == "measured":
            raise ConfigError("the measured-power noise needs the whole population's power at "
                              "every step and runs on one thread: use threads=1 or the "
                              "diffusion noise")
        self._keys = seed_keys(seed, (self._n_batch, self.n_channels))
        self._clock = np.zeros(1, dtype=np.int64)  # steps made: where the noise streams are
        self.blowups = np.zeros(self._n_batch, dtype=np.int64)
        """Per trial: how often the measured-power noise ran away and the trial was put back
        at rest (always 0 under the diffusion noise)."""
        self.v = np.empty((self._n_batch, self.n_channels))
        self.u = np.empty_like(self.v)
        self.reset()
        self._operands = self._named_operands()

    def reset(self) -> None:
        """Membranes back to rest (v = c, u = b·c); the noise streams continue."""
        self.v[:] = self.params.c_mv
        self.u[:] = self.params.b * self.params.c_mv

    def noise_streams(self) -> np.ndarray:
        """Where the noise streams are (a copy: the steps made, which with the seed's keys
        fix every draw to come), for :meth:`restore_noise_streams`."""
        return self._clock.copy()

    def restore_noise_streams(self, streams: np.ndarray) -> None:
        """Put the noise streams back where :meth:`noise_streams` saw them: the draws made
        since then are drawn again."""
        self._clock[:] = streams

    def set_snr(self, snr_db: float) -> None:
        """Change the noise level (dB; inf for none) from the next step on."""
        self._noise_var = self.noise.variance(snr_db)
        self.snr_db = check_snr_db(snr_db)
        self._operands = self._named_operands()

    def step_block(self, current_n: np.ndarray, dt_s: float) -> np.ndarray:
        """Advance ``n_steps`` steps of ``dt_s`` (s) with input forces ``current_n`` (N).

        ``current_n`` is (n_steps, n) — shared by every trial — or (n_steps, batch, n), in
        single (read as it is, as the fused kernels read the leapfrog's forces) or double
        precision; returns bool spikes (n_steps, n) without a batch, else (n_steps, batch, n).
        """
        check_param("dt_s", dt_s, positive("s"))
        cur = np.asarray(current_n)
        if cur.dtype != np.float32:  # single precision (the leapfrog's forces) as it is
            cur = cur.astype(np.float64, copy=False)
        if cur.ndim == 2:
            cur = cur[:, None, :]
        if cur.ndim != 3 or cur.shape[2] != self.n_channels or cur.shape[1] not in (
                1, self._n_batch):
            raise ConfigError(f"current has shape {np.shape(current_n)}; expected "
                              f"(n_steps, {self.n_channels}) or "
                              f"(n_steps, {self._n_batch}, {self.n_channels})")
        spikes = np.empty((cur.shape[0], self._n_batch, self.n_channels), dtype=np.bool_)
        if self.threads > 1:
            numba.set_num_threads(self.threads)
            _izhikevich_parallel_kernel(np.ascontiguousarray(cur), dt_s * 1e3, spikes,
                                        tuple(self.kernel_operands()))
        else:
            _izhikevich_kernel(np.ascontiguousarray(cur), dt_s * 1e3, spikes,
                               tuple(self.kernel_operands()))
        return spikes[:, 0, :] if self.batch is None else spikes

    def kernel_operands(self) -> NeuronOperands:
        """What the compiled step takes after the current, the step (ms) and the spikes
        (:class:`NeuronOperands`; its arrays are updated in place). A Python caller hands a
        kernel ``tuple(...)`` of it, which the kernel names on entry: numba types a plain
        tuple from its C fingerprint, a named one through Python (benchmarks/bench_size.py
        times the call)."""
        return self._operands

    def _named_operands(self) -> NeuronOperands:
        p = self.params
        return NeuronOperands(self.v, self.u, p.a, p.b, p.c_mv, p.d, p.gain, p.v_peak_mv,
                              self.noise.definition == "measured", self._noise_var,
                              self.noise.ref_step_ms, self._keys, self._clock, self.blowups)


def simulate_spikes(forces_n: np.ndarray, dt_s: float, snr_db: float = math.inf,
                    seed: int | np.random.SeedSequence | None = None,
                    params: IzhikevichParams | None = None,
                    noise: NoiseParams | None = None) -> np.ndarray:
    """Spikes for spring forces (N) of shape (n_steps, n) or (batch, n_steps, n), from rest.

    Returns a bool raster of the same shape.
    """
    f = np.asarray(forces_n, dtype=np.float64)
    if f.ndim == 2:
        pop = NeuronPopulation(f.shape[1], params, snr_db, seed, noise=noise)
        return pop.step_block(f, dt_s)
    if f.ndim != 3:
        raise ConfigError(f"forces must be (n_steps, n) or (batch, n_steps, n), got {f.shape}")
    pop = NeuronPopulation(f.shape[2], params, snr_db, seed, batch=f.shape[0], noise=noise)
    return np.ascontiguousarray(pop.step_block(f.transpose(1, 0, 2), dt_s).transpose(1, 0, 2))


MAX_CHANNELS = int(np.iinfo(EVENT_DTYPE["addr"]).max) + 1
"""Channels an event address can name (16-bit: 65,536)."""

SCAN_WORDS = 8
""":func:`_spike_times` tests a raster 8 x 8 bytes at a time (one cache line) for any spike."""


@numba.njit(inline="always")
def _spikes_in(flat: np.ndarray, lo: int, hi: int, n: int, t0_us: int, dt_us: int,
               t: np.ndarray, a: np.ndarray, m: int) -> int:  # pragma: no cover - compiled
    # the spikes among flat[lo:hi] (a raster of n channels, flattened) into t (µs), a from
    # index m on; returns the next index
    for k in range(lo, hi):
        if flat[k]:
            step = k // n
            t[m] = t0_us + step * dt_us
            a[m] = k - step * n
            m += 1
    return m


@numba.njit(cache=True, nogil=True)
def _spike_times(raster: np.ndarray, t0_us: int,
                 dt_us: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    # (t µs, addr) of the spikes of a C-contiguous bool raster (n_steps, n), in raster order:
    # a line of 64 bytes without a spike (nearly all of them at 10 dB) costs one test
    n = raster.shape[1]
    flat = raster.reshape(-1)
    line = SCAN_WORDS * 8
    lines = flat.shape[0] // line
    words = flat[:lines * line].view(np.uint64)
    busy = np.zeros(lines + 1, dtype=np.bool_)
    busy[lines] = True  # the bytes after the last whole line
    for c in range(lines):
        any_spike = np.uint64(0)
        for k in range(SCAN_WORDS):
            any_spike |= words[c * SCAN_WORDS + k]
        busy[c] = any_spike != 0
    room = int(busy.sum()) * line  # at most a spike per byte of the busy lines
    t = np.empty(room, dtype=np.int64)
    a = np.empty(room, dtype=np.uint16)
    m = 0
    for c in range(lines + 1):
        if busy[c]:
            m = _spikes_in(flat, c * line, min((c + 1) * line, flat.shape[0]), n, t0_us,
                           dt_us, t, a, m)
    return t[:m], a[:m]


def raster_to_events(raster: np.ndarray, dt_s: float, t0_us: int = 0) -> np.ndarray:
    """Event array from a bool raster (n_steps, n): spike in step k → ``t = t0 + k·dt`` (µs).

    Events are sorted by time, then address. ``dt_s`` must be a whole number of µs. A
    compiled scan that skips spike-free cache lines: faster than numpy's flat nonzero on a
    tick's few spikes (benchmarks/bench_size.py, ``ev`` column).
    """
    dt_us = _dt_us(dt_s)
    r = np.ascontiguousarray(raster, dtype=np.bool_)
    if r.ndim != 2 or r.shape[1] > MAX_CHANNELS:
        raise ConfigError(f"a raster is (n_steps, n <= {MAX_CHANNELS}), got {r.shape}")
    t, addr = _spike_times(r, int(t0_us), dt_us)
    return make_events(t, addr)


def events_to_raster(events: np.ndarray, n_steps: int, n_channels: int, dt_s: float,
                     t0_us: int = 0) -> np.ndarray:
    """Spike counts (n_steps, n_channels) int from events; events outside are ignored."""
    dt_us = _dt_us(dt_s)
    k = (events["t"] - t0_us) // dt_us
    a = events["addr"].astype(np.int64)
    keep = (k >= 0) & (k < n_steps) & (a < n_channels)
    out = np.zeros((n_steps, n_channels), dtype=np.int64)
    np.add.at(out, (k[keep], a[keep]), 1)
    return out


def _dt_us(dt_s: float) -> int:
    dt_us = int(round(dt_s * 1e6))
    if dt_us <= 0 or abs(dt_us - dt_s * 1e6) > 1e-6:
        raise ConfigError(f"dt_s={dt_s!r} must be a positive whole number of microseconds")
    return dt_us
