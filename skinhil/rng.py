"""Fast seeded Gaussian noise for compiled kernels: xoshiro256+ and the ziggurat method.

numpy's generator costs ~9 ns per normal on the target machine and numba's built-in one
~30 ns; the neuron noise needs two normals per neuron per step (6.8 M/s for one skin in
real time, 1.5 G for the 450-trial benchmark), so the kernels draw their own:

- uniform 64-bit words from xoshiro256+ (Blackman & Vigna), one independent stream per
  state row, seeded through :class:`numpy.random.SeedSequence`;
- standard normals by Marsaglia & Tsang's 128-layer ziggurat (J. Stat. Softw. 5(8), 2000),
  taking the layer and the signed value from disjoint bits of the word, so they are
  independent (Doornik 2005's fix): :func:`next_normal` uses 7 + 32 bits of a word,
  :func:`next_normal_pair` 7 + 25 bits of each half, two normals per word;
- :func:`fill_normal_pairs` draws a row of pairs with the state kept in registers
  (:func:`xoshiro_step`), which a per-draw array state would chain through memory.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_R = 3.442619855899
_V = 9.91256303526217e-3
_M1 = 2147483648.0


def _tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    kn = np.zeros(128, dtype=np.int64)
    wn = np.zeros(128)
    fn = np.zeros(128)
    dn = tn = _R
    q = _V / math.exp(-0.5 * dn * dn)
    kn[0] = int((dn / q) * _M1)
    kn[1] = 0
    wn[0] = q / _M1
    wn[127] = dn / _M1
    fn[0] = 1.0
    fn[127] = math.exp(-0.5 * dn * dn)
    for i in range(126, 0, -1):
        dn = math.sqrt(-2.0 * math.log(_V / dn + math.exp(-0.5 * dn * dn)))
        kn[i + 1] = int((dn / tn) * _M1)
        tn = dn
        fn[i] = math.exp(-0.5 * dn * dn)
        wn[i] = dn / _M1
    return kn, wn, fn


ZIG_KN, ZIG_WN, ZIG_FN = _tables()
ZIG_KN25 = ZIG_KN >> 7
"""Acceptance bounds for a 25-bit signed value (two normals per 64-bit word)."""
ZIG_WN25 = ZIG_WN * 128.0


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
def _normal_slow(state: np.ndarray, hz: np.int64, iz: np.int64) -> float:  # pragma: no cover
    kn, wn, fn = ZIG_KN, ZIG_WN, ZIG_FN
    while True:
        x = hz * wn[iz]
        if iz == 0:
            while True:
                xt = -math.log(next_uniform(state)) / _R
                y = -math.log(next_uniform(state))
                if y + y >= xt * xt:
                    break
            return _R + xt if hz > 0 else -_R - xt
        if fn[iz] + next_uniform(state) * (fn[iz - 1] - fn[iz]) < math.exp(-0.5 * x * x):
            return x
        w = next_u64(state)
        iz = np.int64(w & np.uint64(127))
        hz = np.int64(w >> np.uint64(32)) - 2147483648
        if abs(hz) < kn[iz]:
            return hz * wn[iz]


@numba.njit(inline="always")
def next_normal(state: np.ndarray) -> float:  # pragma: no cover - compiled
    """A standard normal from the stream ``state`` (4 uint64, updated).

    The tables are read as compile-time constants: passing them as arguments makes the
    compiled loop ten times slower.
    """
    kn, wn = ZIG_KN, ZIG_WN
    w = next_u64(state)
    iz = np.int64(w & np.uint64(127))
    hz = np.int64(w >> np.uint64(32)) - 2147483648  # signed 32-bit value, high word
    if abs(hz) < kn[iz]:
        return hz * wn[iz]
    return _normal_slow(state, hz, iz)


@numba.njit(inline="always")
def _layer_and_value(bits: np.uint64) -> tuple[np.int64, np.int64]:  # pragma: no cover
    # 32 random bits → the ziggurat layer (7 bits) and the signed value (25 bits); the fast
    # path accepts when abs(value) < ZIG_KN25[layer], giving value * ZIG_WN25[layer]
    return (np.int64(bits & np.uint64(127)),
            np.int64((bits >> np.uint64(7)) & np.uint64(0x1FFFFFF)) - 16777216)


@numba.njit(inline="always")
def _normal_from_bits(bits: np.uint64, s0: np.uint64, s1: np.uint64, s2: np.uint64,
                      s3: np.uint64, spill: np.ndarray) -> tuple[
                          float, np.uint64, np.uint64, np.uint64, np.uint64]:  # pragma: no cover
    # a standard normal from 32 random bits (7 for the layer, 25 for the signed value) and
    # the stream state, updated; the rare rejections draw more words through ``spill``
    iz, hz = _layer_and_value(bits)
    if abs(hz) < ZIG_KN25[iz]:
        return hz * ZIG_WN25[iz], s0, s1, s2, s3
    spill[0], spill[1], spill[2], spill[3] = s0, s1, s2, s3
    z = _normal_slow(spill, hz * 128, iz)
    return z, spill[0], spill[1], spill[2], spill[3]


@numba.njit(inline="always")
def normal_pair(s0: np.uint64, s1: np.uint64, s2: np.uint64, s3: np.uint64,
                spill: np.ndarray) -> tuple[float, float, np.uint64, np.uint64, np.uint64,
                                            np.uint64]:  # pragma: no cover - compiled
    """Two independent standard normals from one 64-bit word (and rarely more) of the stream
    held in ``s0..s3``: ``(z1, z2, s0, s1, s2, s3)``; ``spill`` is 4 uint64 of scratch."""
    w, s0, s1, s2, s3 = xoshiro_step(s0, s1, s2, s3)
    z1, s0, s1, s2, s3 = _normal_from_bits(w & np.uint64(0xFFFFFFFF), s0, s1, s2, s3, spill)
    z2, s0, s1, s2, s3 = _normal_from_bits(w >> np.uint64(32), s0, s1, s2, s3, spill)
    return z1, z2, s0, s1, s2, s3


@numba.njit(inline="always")
def next_normal_pair(state: np.ndarray) -> tuple[float, float]:  # pragma: no cover
    """Two independent standard normals from one 64-bit word of ``state`` (and rarely more)."""
    z1, z2, s0, s1, s2, s3 = normal_pair(state[0], state[1], state[2], state[3], state)
    state[0], state[1], state[2], state[3] = s0, s1, s2, s3
    return z1, z2


@numba.njit
def _finish_pair(spill: np.ndarray, lo: np.uint64,
                 hi: np.uint64) -> tuple[float, float]:  # pragma: no cover - compiled
    # the pair of the word's halves lo, hi when one of them is rejected by the fast test:
    # each half as _normal_from_bits takes it, the stream in spill (updated)
    z1, s0, s1, s2, s3 = _normal_from_bits(lo, spill[0], spill[1], spill[2], spill[3], spill)
    spill[0], spill[1], spill[2], spill[3] = s0, s1, s2, s3
    z2, s0, s1, s2, s3 = _normal_from_bits(hi, spill[0], spill[1], spill[2], spill[3], spill)
    spill[0], spill[1], spill[2], spill[3] = s0, s1, s2, s3
    return z1, z2


@numba.njit(cache=True)
def fill_normal_pairs(state: np.ndarray, first: np.ndarray,
                      second: np.ndarray) -> None:  # pragma: no cover - compiled
    """Fill ``first[i], second[i]`` with pair ``i`` of standard normals from the stream
    ``state`` (4 uint64, updated): the same draws as ``next_normal_pair`` in a loop, with
    one test for the pair's fast path and the rare rest (5 % of pairs) out of line."""
    spill = np.empty(4, dtype=np.uint64)
    s0, s1, s2, s3 = state[0], state[1], state[2], state[3]
    for i in range(first.shape[0]):
        w, s0, s1, s2, s3 = xoshiro_step(s0, s1, s2, s3)
        lo = w & np.uint64(0xFFFFFFFF)
        hi = w >> np.uint64(32)
        iz1, hz1 = _layer_and_value(lo)
        iz2, hz2 = _layer_and_value(hi)
        if abs(hz1) < ZIG_KN25[iz1] and abs(hz2) < ZIG_KN25[iz2]:
            first[i] = hz1 * ZIG_WN25[iz1]
            second[i] = hz2 * ZIG_WN25[iz2]
        else:
            spill[0], spill[1], spill[2], spill[3] = s0, s1, s2, s3
            first[i], second[i] = _finish_pair(spill, lo, hi)
            s0, s1, s2, s3 = spill[0], spill[1], spill[2], spill[3]
    state[0], state[1], state[2], state[3] = s0, s1, s2, s3


@numba.njit(cache=True)
def fill_normal(state: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """Fill the 1-D ``out`` with standard normals from the stream ``state`` (for tests)."""
    for i in range(0, out.shape[0] - 1, 2):
        out[i], out[i + 1] = next_normal_pair(state)
    if out.shape[0] % 2:
        out[-1] = next_normal(state)
