"""Fast seeded Gaussian noise for compiled kernels: xoshiro256+ and a 1,024-layer ziggurat.

numpy's generator costs ~9 ns per normal on the target machine and numba's built-in one
~30 ns; the neuron noise needs two normals per neuron per step (6.8 M/s for one skin in
real time, 1.5 G for the 450-trial benchmark), so the kernels draw their own:

- uniform 64-bit words from xoshiro256+ (Blackman & Vigna), one independent stream per
  state row, seeded through :class:`numpy.random.SeedSequence`;
- standard normals by the ziggurat method (Marsaglia & Tsang, J. Stat. Softw. 5(8), 2000)
  with ``N_LAYERS`` = 1,024 layers of equal area, two normals per 64-bit word: each 32-bit
  half gives the layer (its top 10 bits) and a signed 22-bit value (the other bits), so they
  are independent (Doornik 2005's fix). 99.57 % of normals take the fast path (one compare, one
  multiply); the rest go through the wedge or tail test (~40 ns). Marsaglia & Tsang's 128
  layers send 2.8 % there, which made a pair 1.5x dearer (3.55 against 2.32 ns);
- :func:`fill_normal_pairs` draws a row of pairs with the state kept in registers
  (:func:`xoshiro_step`), which a per-draw array state would chain through memory, and tests
  both halves of a word with one unsigned compare each (:data:`ZIG_LOW`, :data:`ZIG_SPAN`):
  1.78 ns per pair against 2.08 for the test spelled out (34x34 skin, 17,866 pairs a row).
"""

from __future__ import annotations

import math

import numba
import numpy as np

LAYER_BITS = 10
"""Bits of a 32-bit draw that pick the ziggurat layer; the other 22 are a signed value."""
N_LAYERS = 1 << LAYER_BITS
_VALUE_HALF = 1 << (31 - LAYER_BITS)
"""2^21: the signed value of a draw lies in [−2^21, 2^21)."""


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


ZIG_R, ZIG_KN, ZIG_WN, ZIG_FN = _tables(N_LAYERS)
"""The base layer's edge (≈ 4.04) and the tables of the 1,024-layer ziggurat."""


def seed_states(seed: int | np.random.SeedSequence | None, n_streams: int) -> np.ndarray:
    """(n_streams, 4) uint64 xoshiro256+ states, independent streams derived from ``seed``."""
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    words = ss.generate_state(4 * max(n_streams, 1), dtype=np.uint64).reshape(-1, 4)
    words[np.all(words == 0, axis=1), 0] = np.uint64(1)  # the all-zero state is forbidden
    return words[:n_streams].copy()


@numba.njit(inline="always")
def _rotl(x: np.uint64, k: int) -> np.uint64:  # pragma: no cover - compiled
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@numba.njit(inline="always")
def xoshiro_step(s0: np.uint64, s1: np.uint64, s2: np.uint64,
                 s3: np.uint64) -> tuple[np.uint64, np.uint64, np.uint64, np.uint64,
                                         np.uint64]:  # pragma: no cover - compiled
    """One xoshiro256+ step on a state held in four scalars: ``(word, s0, s1, s2, s3)``.

    Loops that draw many words keep the state in these scalars (registers) rather than in
    an array, whose stores and reloads would otherwise chain every draw through memory.
    """
    result = s0 + s3
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    return result, s0, s1, s2, s3


@numba.njit(inline="always")
def next_u64(state: np.ndarray) -> np.uint64:  # pragma: no cover - compiled
    """Next 64-bit word of the xoshiro256+ stream held in ``state`` (4 uint64, updated)."""
    result, s0, s1, s2, s3 = xoshiro_step(state[0], state[1], state[2], state[3])
    state[0], state[1], state[2], state[3] = s0, s1, s2, s3
    return result


@numba.njit(inline="always")
def next_uniform(state: np.ndarray) -> float:  # pragma: no cover - compiled
    """A uniform double in (0, 1) from the stream ``state``."""
    return ((next_u64(state) >> np.uint64(11)) + 0.5) * (1.0 / 9007199254740992.0)


@numba.njit(inline="always")
def _layer_and_value(bits: np.uint64) -> tuple[np.int64, np.int64]:  # pragma: no cover
    # 32 random bits → the ziggurat layer (the top 10) and the signed value (the low 22, so
    # that xoshiro256+'s weak lowest bits only touch the value's last digits); the fast path
    # accepts when abs(value) < ZIG_KN[layer], giving value * ZIG_WN[layer]
    return (np.int64(bits >> np.uint64(32 - LAYER_BITS)),
            np.int64(bits & np.uint64(2 * _VALUE_HALF - 1)) - _VALUE_HALF)


@numba.njit(inline="always")
def _normal_slow(state: np.ndarray, hz: np.int64, iz: np.int64) -> float:  # pragma: no cover
    # the draw (layer iz, value hz) missed the fast path: the tail beyond ZIG_R (layer 0) or
    # the wedge test, and a fresh 32-bit draw from ``state`` while rejected
    kn, wn, fn, r = ZIG_KN, ZIG_WN, ZIG_FN, ZIG_R
    while True:
        x = hz * wn[iz]
        if iz == 0:
            while True:
                xt = -math.log(next_uniform(state)) / r
                y = -math.log(next_uniform(state))
                if y + y >= xt * xt:
                    break
            return r + xt if hz > 0 else -r - xt
        if fn[iz] + next_uniform(state) * (fn[iz - 1] - fn[iz]) < math.exp(-0.5 * x * x):
            return x
        iz, hz = _layer_and_value(next_u64(state) >> np.uint64(32))
        if abs(hz) < kn[iz]:
            return hz * wn[iz]


@numba.njit
def _finish_pair(spill: np.ndarray, lo: np.uint64,
                 hi: np.uint64) -> tuple[float, float]:  # pragma: no cover - compiled
    # the pair of the word's halves lo, hi when one of them missed the fast path: each half
    # in turn, the stream in spill (updated) for the slow path's draws
    iz, hz = _layer_and_value(lo)
    z1 = hz * ZIG_WN[iz] if abs(hz) < ZIG_KN[iz] else _normal_slow(spill, hz, iz)
    iz, hz = _layer_and_value(hi)
    z2 = hz * ZIG_WN[iz] if abs(hz) < ZIG_KN[iz] else _normal_slow(spill, hz, iz)
    return z1, z2


def _fast_windows(kn: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # the fast path's test |value| < kn[layer] on the unsigned 22-bit field u = value + 2^21,
    # as one unsigned compare: u − low[layer] < span[layer] with low = 2^21 − kn + 1 and
    # span = 2·kn − 1 (0 for the top layer, kn = 0: never taken); a u below low wraps past
    # every span (numba subtracts two uint32 as uint64)
    low = (_VALUE_HALF - kn + 1).astype(np.uint32)
    span = np.where(kn > 0, 2 * kn - 1, 0).astype(np.uint32)
    return low, span


ZIG_LOW, ZIG_SPAN = _fast_windows(ZIG_KN)
"""Per layer, the fast path's window on the unsigned 22-bit field (:func:`_fast_windows`)."""


@numba.njit(cache=True)
def fill_normal_pairs(state: np.ndarray, first: np.ndarray,
                      second: np.ndarray) -> None:  # pragma: no cover - compiled
    """Fill ``first[i], second[i]`` with pair ``i`` of standard normals from the stream
    ``state`` (4 uint64, updated): one 64-bit word per pair, its low half for ``first``, its
    high half for ``second``, and, for the 0.9 % of pairs that miss the fast path, further
    words out of line.

    The fast path is :func:`_layer_and_value`'s test ``|value| < ZIG_KN[layer]`` done on
    32-bit halves as one unsigned compare per half (:data:`ZIG_LOW`, :data:`ZIG_SPAN`) and both
    halves' results written before the test: the same normals as the test spelled out
    (tests/test_core_neurons.py), in 15 % less time."""
    spill = np.empty(4, dtype=np.uint64)
    low, span, wn = ZIG_LOW, ZIG_SPAN, ZIG_WN
    mask = np.uint32(2 * _VALUE_HALF - 1)
    shift = np.uint32(32 - LAYER_BITS)
    s0, s1, s2, s3 = state[0], state[1], state[2], state[3]
    for i in range(first.shape[0]):
        w, s0, s1, s2, s3 = xoshiro_step(s0, s1, s2, s3)
        lo = np.uint32(w & np.uint64(0xFFFFFFFF))
        hi = np.uint32(w >> np.uint64(32))
        iz1, u1 = lo >> shift, lo & mask
        iz2, u2 = hi >> shift, hi & mask
        first[i] = (np.int32(u1) - np.int32(_VALUE_HALF)) * wn[iz1]
        second[i] = (np.int32(u2) - np.int32(_VALUE_HALF)) * wn[iz2]
        if not (((u1 - low[iz1]) < span[iz1]) & ((u2 - low[iz2]) < span[iz2])):
            spill[0], spill[1], spill[2], spill[3] = s0, s1, s2, s3
            first[i], second[i] = _finish_pair(spill, np.uint64(lo), np.uint64(hi))
            s0, s1, s2, s3 = spill[0], spill[1], spill[2], spill[3]
    state[0], state[1], state[2], state[3] = s0, s1, s2, s3


def fill_normal(state: np.ndarray, out: np.ndarray) -> None:
    """Fill the 1-D ``out`` with standard normals from the stream ``state`` (for tests): the
    pairs of :func:`fill_normal_pairs`, first halves then second halves."""
    pairs = -(-out.shape[0] // 2)
    first, second = np.empty(pairs), np.empty(pairs)
    fill_normal_pairs(state, first, second)
    out[:] = np.concatenate([first, second])[:out.shape[0]]
