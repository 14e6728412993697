"""Touch-down or release: which springs an onset's burst of spikes excites.

The onset rule (:mod:`skinhil.receiver.onset`) fires on any rise of the population's
firing: a touch-down, but also the release of a held touch (its rebound fires a burst as
large) and, at the paper's 10 dB, the noise. The skin and its neurons tell the first two
apart. A press pushes the surface down: the in-layer springs around the contact stretch
(tension excites their neurons, signed Hooke force, :mod:`skinhil.model.sensor`), while
most springs between the layers under it are compressed (compression inhibits). When the
object lets go the forces fall back to zero without overshoot, and the neurons the hold
inhibited fire a rebound (the Izhikevich neuron's post-inhibitory rebound: its recovery
variable ``u`` fell while ``v`` was held down, so ``v`` overshoots once the inhibition ends:
without noise a lone neuron held at -0.066 N for 150 ms fires 13 ms after it is let go),
while the stretched in-layer ones fall silent. Measured on the default skin (the presses of
``examples/scenarios/task_force.toml`` at 10 dB, seeds 1-6; forces of a 0.7 N hold): the ten
channels that fire most in the 25 ms after a touch-down are all in tension during the hold
(+0.010..+0.015 N), nine of them in-layer springs; the ten that fire most after a release
are all between-layer springs held in compression (-0.050..-0.066 N). The noise fires both kinds
alike.

So the rule (:func:`touch_kind`), on the spikes of an onset's first :data:`KIND_S` from its
decision window's start: more spikes of in-layer springs than of between-layer springs is a
**touch-down**, more of between-layer springs a **release**, as many of each is neither.
Nothing is fitted but the burst's length (:data:`KIND_S`); measured on the calibration runs
by ``benchmarks/fit_touch_kind.py`` (docs/tasks.md). No ground truth is used.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from skinhil.model.geometry import MeshSize, build_mesh

TOUCH_DOWN = "touch-down"
"""An onset whose burst excites the skin's in-layer springs: a press begins."""
RELEASE = "release"
"""An onset whose burst excites the springs between the layers: a held touch ends."""
KIND_S = 0.04
"""The onset's burst is read this long (s) from its decision window's start (within the
receiver's 50 ms window). Chosen among 15, 25 and 40 ms on the task scenarios' calibration
runs at 10 dB, seeds 1-6, as the length that calls the most touch-downs touch-downs and
releases releases: ``python benchmarks/fit_touch_kind.py --snr-db 10 --seeds 1,2,3,4,5,6``
(40 ms: 97 % of the 512 onsets found at a touch-down called touch-down, 97 % of the 303 at a
release called release, 2 % of those mistaken for a touch-down; 25 ms: 95, 96 and 3 %;
15 ms: 92, 95 and 5 %)."""
IN_LAYER_MAX = 3
""":attr:`skinhil.model.geometry.Mesh.layer_of_spring` is 1, 2 or 3 for the in-layer springs
(12 and 23 between the layers)."""


@lru_cache(maxsize=8)
def in_layer(size: MeshSize) -> np.ndarray:
    """(n_channels,) bool: the sensors (springs) of a skin of top layer ``size`` that lie
    within a layer (the others join two layers)."""
    mesh = build_mesh(1.0, 1.0, size)
    out = mesh.layer_of_spring <= IN_LAYER_MAX
    out.flags.writeable = False
    return out


def touch_kind(t_us: np.ndarray, addr: np.ndarray, start_us: int, in_layer_mask: np.ndarray,
               kind_s: float = KIND_S) -> str | None:
    """:data:`TOUCH_DOWN`, :data:`RELEASE` or None (neither: as many spikes of each kind of
    spring, noise) for the onset whose decision window starts at ``start_us`` (µs), from the
    spikes (times ``t_us`` µs, channels ``addr``) of its first ``kind_s`` (s);
    ``in_layer_mask`` is :func:`in_layer` of the skin's size."""
    t = np.asarray(t_us, dtype=np.int64)
    a = np.asarray(addr, dtype=np.int64)
    a = a[(t >= start_us) & (t < start_us + int(round(kind_s * 1e6)))
          & (a < in_layer_mask.shape[0])]
    within = int(np.count_nonzero(in_layer_mask[a]))
    between = a.shape[0] - within
    if within > between:
        return TOUCH_DOWN
    if between > within:
        return RELEASE
    return None
