"""Seeded Gaussian noise that compiled loops vectorise: a counter-based generator and a
2,048-layer ziggurat with a branch-free fast path.

The neuron noise needs two standard normals per neuron per step (6.8 M/s for the 6x6 skin in
real time, 357 M/s for a 34x34 skin, 1.5 G for the 450-trial benchmark). A generator that
carries its state from draw to draw (xoshiro, numpy's PCG64) chains every draw to the one
before it, so a loop over the channels runs one draw at a time. Here a draw is a pure
function of where it is used:

- **Counter-based words.** The 64-bit word of channel ``i`` at step ``k`` is
  ``mix64(key[i] ^ step_hash(k))``: ``key`` holds one random 64-bit key per channel (and per
  trial), derived from the seed by :class:`numpy.random.SeedSequence` (:func:`seed_keys`);
  ``step_hash(k) = mix64((k + 1)·γ)`` is SplitMix64's k-th output, and ``mix64`` is SplitMix64's
  output function (Steele, Lea & Flood, OOPSLA 2014; Stafford's "Mix13" constants), a bijection
  of 64-bit words whose every output bit depends on every input bit. No draw depends on
  another, so a loop over the channels vectorises (8 channels per AVX-512 instruction), any
  block of channels on any thread draws the same numbers, and a stream's position is the step
  count alone (:meth:`~skinhil.model.neurons.NeuronPopulation.noise_streams`). Two channels
  or steps share a word only by a chance coincidence of two 64-bit values (the keys are
  random), never along a run: XOR with a hashed step does not shift one channel's sequence
  onto another's as adding a multiple of γ would.
- **Standard normals by the ziggurat** (Marsaglia & Tsang, J. Stat. Softw. 5(8), 2000) with
  ``N_LAYERS`` = 2,048 layers of equal area, two normals per word: each 32-bit half gives the
  layer (its top 11 bits) and a signed 21-bit value (the low 21 bits), so the two are
  independent (Doornik 2005's fix). The fast path (99.77 % of normals) is one table load, one
  compare and one multiply, with no branch: :data:`ZIG_TABLE` holds per layer the multiplier
  ``wn`` as a double whose lowest 21 mantissa bits are the fast path's bound ``kn`` (the
  multiplier moves by < 2^-31 of itself, and is defined as the packed double, so the fast and
  the slow path use the same one), so one gathered word gives both. The table is 16 KiB: with
  1,024 layers (8 KiB) twice as many pairs miss the fast path (0.85 %), with 4,096 (32 KiB) it
  fills the first-level cache; 2,048 is the fastest of the three
  (benchmarks/bench_core.py times the neurons).
- **The slow path** (the wedges and the tail beyond :data:`ZIG_R`, 0.23 % of normals, 0.45 %
  of pairs) runs outside the vectorised loop (:func:`normal_pair`, inlined into the
  kernel's second pass): its uniforms come from a SplitMix64
  sub-stream seeded by the word's own input and the half, so it too depends on nothing but
  ``(key, k)``.

A kernel's loop calls :func:`fast_pair` on every channel, keeps the channels whose pair
missed the fast path for a second pass that calls :func:`normal_pair` on them alone, and
draws exactly what :func:`normal_pair` gives for every channel (tests/test_core_rng.py).
"""

from __future__ import annotations

import math

import numba
import numpy as np

LAYER_BITS = 11
"""Bits of a 32-bit draw that pick the ziggurat layer; the other 21 are a signed value."""
N_LAYERS = 1 << LAYER_BITS
VALUE_BITS = 32 - LAYER_BITS
_VALUE_HALF = 1 << (VALUE_BITS - 1)
"""2^20: the signed value of a draw lies in [−2^20, 2^20)."""
_KN_MASK = (1 << VALUE_BITS) - 1

GAMMA = np.uint64(0x9E3779B97F4A7C15)
"""SplitMix64's increment (2^64 / golden ratio, odd)."""
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
SLOW_SALTS = (np.uint64(0x5851F42D4C957F2D), np.uint64(0x2545F4914F6CDD1D))
"""XORed into a word's input to seed the slow path's sub-stream of its low and high half."""


def _density(x: float) -> float:
    return math.exp(-0.5 * x * x)


def _layer_area(r: float) -> float:
    # the base layer's area for the edge r: the rectangle r·f(r) and the tail beyond r
    return r * _density(r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))


def _top_gap(r: float, n_layers: int) -> float:
    # stack n_layers strips of the base layer's area under the unnormalised density from
    # the base edge r upwards: > 0 if they reach the top too soon (r too small), < 0 if the
    # top strip is left short (r too large), 0 at the ziggurat's edge
    area = _layer_area(r)
    x = r
    for _ in range(n_layers - 2):
        y = area / x + _density(x)
        if y >= 1.0:
            return 1.0
        x = math.sqrt(-2.0 * math.log(y))
    return area / x + _density(x) - 1.0


def _ziggurat_edge(n_layers: int) -> tuple[float, float]:
    """``(r, area)``: the base layer's edge and every layer's area for ``n_layers`` layers."""
    lo, hi = 2.0, 6.0
    for _ in range(64):  # bisection to the last bit (4 / 2^64)
        mid = 0.5 * (lo + hi)
        if _top_gap(mid, n_layers) > 0.0:
            lo = mid
        else:
            hi = mid
    r = hi  # the side whose strips all fit under the top
    return r, _layer_area(r)


def _tables(n_layers: int) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    # Marsaglia & Tsang's tables for a signed value of ±_VALUE_HALF: layer i accepts
    # |value| < kn[i] at once, as value·wn[i]; fn[i] is the density at the layer's edge
    r, area = _ziggurat_edge(n_layers)
    scale = float(_VALUE_HALF)
    kn = np.zeros(n_layers, dtype=np.int64)
    wn = np.zeros(n_layers)
    fn = np.zeros(n_layers)
    dn = tn = r
    q = area / _density(dn)
    kn[0] = int((dn / q) * scale)
    kn[1] = 0  # the top layer has no part wholly under the curve
    wn[0] = q / scale
    wn[-1] = dn / scale
    fn[0] = 1.0
    fn[-1] = _density(dn)
    for i in range(n_layers - 2, 0, -1):
        dn = math.sqrt(-2.0 * math.log(area / dn + _density(dn)))
        kn[i + 1] = int((dn / tn) * scale)
        tn = dn
        fn[i] = _density(dn)
        wn[i] = dn / scale
    return r, kn, wn, fn


def _packed(kn: np.ndarray, wn: np.ndarray) -> np.ndarray:
    # per layer the multiplier wn as a double whose lowest VALUE_BITS mantissa bits hold kn
    # (< 2^20): one table word gives the fast path both
    bits = wn.view(np.uint64) & ~np.uint64(_KN_MASK)
    return bits | kn.astype(np.uint64)


ZIG_R, _KN, _WN, ZIG_FN = _tables(N_LAYERS)
"""The base layer's edge (≈ 4.22) and the density at every layer's edge."""
ZIG_TABLE = _packed(_KN, _WN)
"""Per layer, the fast path's word: the multiplier (a double) with the bound in its low bits."""
ZIG_WN = ZIG_TABLE.view(np.float64)
"""Per layer, what the signed value is multiplied by (the packed word as a double)."""
ZIG_KN = (ZIG_TABLE & np.uint64(_KN_MASK)).astype(np.int64)
"""Per layer, the fast path's bound: ``|value| < ZIG_KN[layer]`` takes ``value·ZIG_WN[layer]``."""


TAIL_BOUND = math.sqrt(-2.0 * math.log(2.0**-33))
"""The largest |z| a normal reaches: the radius of the smallest uniform, u = 2^-33 (≈ 6.7637)."""


def seed_keys(seed: int | np.random.SeedSequence | None, shape: int | tuple[int, ...]
              ) -> np.ndarray:
    """Random uint64 keys of ``shape`` (one per channel and trial) derived from ``seed``."""
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    size = int(np.prod(shape))
    return ss.generate_state(max(size, 1), dtype=np.uint64)[:size].reshape(shape)


@numba.njit(inline="always")
def mix64(z: np.uint64) -> np.uint64:  # pragma: no cover - compiled
    """SplitMix64's output function: a bijection of 64-bit words with full avalanche."""
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


@numba.njit(inline="always")
def step_hash(step: int) -> np.uint64:  # pragma: no cover - compiled
    """What every channel's key is XORed with at ``step`` (0, 1, ...): SplitMix64's output
    number ``step`` from state 0."""
    return mix64(np.uint64(step + 1) * GAMMA)


@numba.njit(inline="always")
def _half(w: np.uint64, high: bool) -> tuple[np.intp, np.int64]:  # pragma: no cover
    # (layer, signed value) of the word's low or high 32 bits: the layer its top LAYER_BITS,
    # the value its low VALUE_BITS read as a signed number
    h = w >> np.uint64(32) if high else w & np.uint64(0xFFFFFFFF)
    iz = np.intp(h >> np.uint64(VALUE_BITS))
    hz = np.int64((h & np.uint64(_KN_MASK)) ^ np.uint64(_VALUE_HALF)) - _VALUE_HALF
    return iz, hz


@numba.njit(inline="always")
def _fast(iz: np.intp, hz: np.int64) -> tuple[float, bool]:  # pragma: no cover - compiled
    # the fast path of one half: (value·multiplier, whether |value| is within the bound)
    t = ZIG_TABLE[iz]
    return (float(hz * np.uint64(t).view(np.float64)),
            bool(abs(hz) < np.int64(t & np.uint64(_KN_MASK))))


@numba.njit(inline="always")
def fast_pair(w: np.uint64) -> tuple[float, float, bool, bool]:  # pragma: no cover
    """The fast path on both halves of word ``w``: ``(z1, z2, ok1, ok2)``, each ``z`` the
    standard normal of its half where its ``ok`` holds (branch-free: vectorises)."""
    iz1, hz1 = _half(w, False)
    iz2, hz2 = _half(w, True)
    z1, ok1 = _fast(iz1, hz1)
    z2, ok2 = _fast(iz2, hz2)
    return z1, z2, ok1, ok2


@numba.njit(inline="always")
def _uniform(s: np.uint64) -> tuple[float, np.uint64]:  # pragma: no cover - compiled
    # the sub-stream s's next uniform double in (0, 1), and its next state
    s = s + GAMMA
    return ((mix64(s) >> np.uint64(11)) + 0.5) * (1.0 / 9007199254740992.0), s


@numba.njit(inline="always")
def _normal_slow(iz: np.intp, hz: np.int64, s: np.uint64) -> float:  # pragma: no cover
    # the draw (layer iz, value hz) missed the fast path: the tail beyond ZIG_R (layer 0) or
    # the wedge test, and a fresh 32-bit draw while rejected; uniforms from sub-stream s
    r = ZIG_R
    while True:
        x = hz * ZIG_WN[iz]
        if iz == 0:
            while True:
                u1, s = _uniform(s)
                u2, s = _uniform(s)
                xt = -math.log(u1) / r
                if -2.0 * math.log(u2) >= xt * xt:
                    break
            return r + xt if hz > 0 else -r - xt
        u, s = _uniform(s)
        if ZIG_FN[iz] + u * (ZIG_FN[iz - 1] - ZIG_FN[iz]) < math.exp(-0.5 * x * x):
            return x
        s = s + GAMMA
        iz, hz = _half(mix64(s), True)
        z, ok = _fast(iz, hz)
        if ok:
            return z


@numba.njit(inline="always", nogil=True)
def normal_pair(key: np.uint64, step: int) -> tuple[float, float]:  # pragma: no cover
    """The pair of standard normals of the channel with ``key`` at ``step``: the fast path of
    :func:`fast_pair` where it holds, else the slow path. Inlined, slow path included, where
    a kernel calls it: a call out of line per miss slows the neurons' kernel for the same
    draws (benchmarks/bench_size.py, ``neur`` column)."""
    x = key ^ step_hash(step)
    w = mix64(x)
    z1, z2, ok1, ok2 = fast_pair(w)
    if not ok1:
        iz, hz = _half(w, False)
        z1 = _normal_slow(iz, hz, mix64(x ^ SLOW_SALTS[0]))
    if not ok2:
        iz, hz = _half(w, True)
        z2 = _normal_slow(iz, hz, mix64(x ^ SLOW_SALTS[1]))
    return z1, z2


@numba.njit(cache=True, nogil=True)
def fill_normal_pairs(keys: np.ndarray, step: int, first: np.ndarray,
                      second: np.ndarray) -> None:  # pragma: no cover - compiled
    """``first[i], second[i]``: the pair of the channel with ``keys[i]`` at ``step``
    (:func:`normal_pair`), the fast path over every channel, then the misses alone."""
    h = step_hash(step)
    n = keys.shape[0]
    missed = 0
    for i in range(n):
        z1, z2, ok1, ok2 = fast_pair(mix64(keys[i] ^ h))
        first[i] = z1
        second[i] = z2
        missed += not (ok1 & ok2)
    if missed:
        for i in range(n):
            z1, z2, ok1, ok2 = fast_pair(mix64(keys[i] ^ h))
            if not (ok1 & ok2):
                first[i], second[i] = normal_pair(keys[i], step)


def fill_normal(keys: np.ndarray, step: int, out: np.ndarray) -> None:
    """Fill the 1-D ``out`` with standard normals (for tests): the pairs of ``keys`` at
    ``step`` (:func:`fill_normal_pairs`), first halves then second halves."""
    pairs = -(-out.shape[0] // 2)
    if keys.shape[0] < pairs:
        raise ValueError(f"{out.shape[0]} normals need {pairs} keys, got {keys.shape[0]}")
    first, second = np.empty(pairs), np.empty(pairs)
    fill_normal_pairs(keys[:pairs], step, first, second)
    out[:] = np.concatenate([first, second])[:out.shape[0]]
