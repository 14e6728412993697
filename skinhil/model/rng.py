"""The neurons' Gaussian noise: a counter-based 64-bit word per channel and step, turned into
two standard normals by Box-Muller in float32 (the C kernel :mod:`skinhil.model.normals`).

The neuron noise needs two standard normals per neuron per step (357 M/s for a 34x34 skin in
real time). A generator that carries its state from draw to draw chains every draw to the one
before it; here a draw is a pure function of the channel's key and the step:

- **Counter-based words.** The 64-bit word of channel ``i`` at step ``k`` is
  ``w = mix64(key[i] ^ step_hash(k))``: ``key`` holds one random 64-bit key per channel (and
  per trial), derived from the seed by :class:`numpy.random.SeedSequence` (:func:`seed_keys`);
  ``step_hash(k) = mix64((k + 1)·γ)`` is SplitMix64's k-th output, and ``mix64`` is
  SplitMix64's output function (Steele, Lea & Flood, OOPSLA 2014; Stafford's "Mix13"
  constants), a bijection of 64-bit words whose every output bit depends on every input bit.
  No draw depends on another, so any block of channels on any thread, on any machine, draws
  the same numbers, and a stream's position is the step count alone
  (:meth:`~skinhil.model.neurons.NeuronPopulation.noise_streams`).
- **Box-Muller in float32** on the word's halves ``lo`` (low 32 bits) and ``hi`` (high 32):
  ``u = (lo + 1/2)·2^-32`` (float32 arithmetic, correctly rounded), the radius
  ``r = sqrt(-2 ln u)``; the angle ``θ = (q + (a + 1/2)·2^-23)·π/2`` with the quadrant ``q`` the
  top 2 bits of ``hi`` and ``a`` its next 23 bits; the pair is ``(r cos θ, r sin θ)``. ln, sin
  and cos are the kernel's own float32 polynomials (Cephes' logf on the mantissa; Taylor
  series to the 13th and 12th power within the quadrant), every multiply-add fused: the
  normals are the same bits on every machine and every path of the kernel
  (tests/test_normals_kernel.py), and within 2^-16 of the float64 formula above.
- **The tail bound.** The smallest ``u`` is 2^-33, so no normal exceeds
  :data:`TAIL_BOUND` = sqrt(66 ln 2) ≈ 6.7637 in magnitude (a standard normal exceeds it with
  probability 1.3·10^-11); the tails up to there follow the normal's probabilities.
"""

from __future__ import annotations

import math

import numba
import numpy as np

GAMMA = np.uint64(0x9E3779B97F4A7C15)
"""SplitMix64's increment (2^64 / golden ratio, odd)."""
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)

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
