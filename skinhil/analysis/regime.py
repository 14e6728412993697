"""How large the deformation is: the relative displacement of each spring's ends over its
rest length, and where the small-displacement (axial) readout stops agreeing with the length.

For spring ``s`` between masses ``i`` and ``j`` the relative displacement is
``|q_j − q_i| / L0`` (``q`` the displacements from rest, ``L0`` the rest length). The
linear mechanics' stiffness matrix and its axial readout are the first-order terms in this
ratio: they hold while it is small. :func:`largest_relative_displacement` measures it on the
model's own stepper (either mechanics) over a stimulus; :func:`readout_gap` compares the two
readouts of the same dynamics as the force grows.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from skinhil.model.skin import SkinModel
from skinhil.model.stimuli import Stimulus

SAMPLE_STEPS = 5
"""Steps of ``dt_s`` between two looks at the displacements (0.5 ms at 0.1 ms steps: the
mesh's fastest ringing at the defaults, ~1 kHz, is still seen at its peaks within a few %)."""


@dataclass(frozen=True)
class Deformation:
    """The largest ``|q_j − q_i| / L0`` of a run (dimensionless), at which spring (0-based)
    and time (s)."""

    ratio: float
    spring: int
    t_s: float


def largest_relative_displacement(model: SkinModel, stimulus: Stimulus, duration_s: float,
                                  dt_s: float = 1e-4) -> Deformation:
    """Step ``model`` from rest under ``stimulus`` for ``duration_s`` (s) at ``dt_s`` (s) and
    return the largest relative displacement of any spring, looked at every
    :data:`SAMPLE_STEPS` steps."""
    model.check_stimulus(stimulus)
    stepper = model.stepper(dt_s)
    i, j = model.springs[:, 0], model.springs[:, 1]
    rest = np.linalg.norm(model.positions[j] - model.positions[i], axis=1)
    n_steps = max(1, int(round(duration_s / dt_s)))
    best = Deformation(0.0, 0, 0.0)
    for start in range(0, n_steps, SAMPLE_STEPS):
        n = min(SAMPLE_STEPS, n_steps - start)
        stepper.advance(stimulus.force_at((start + np.arange(n)) * dt_s))
        q = stepper.displacement_m()
        ratio = np.linalg.norm(q[j] - q[i], axis=1) / rest
        s = int(np.argmax(ratio))
        if ratio[s] > best.ratio:
            best = Deformation(float(ratio[s]), s, (start + n) * dt_s)
    return best


def readout_gap(model: SkinModel, stimulus: Stimulus, duration_s: float,
                dt_s: float = 1e-4) -> float:
    """How far the axial readout is from the length readout on ``model``'s dynamics under
    ``stimulus``: max |length − axial| / max |length| over the run (dimensionless)."""
    length, axial = (SkinModel(replace(model.params, readout=r)).simulate(stimulus,
                                                                          duration_s, dt_s)
                     for r in ("length", "axial"))
    return float(np.abs(length - axial).max() / max(np.abs(length).max(), 1e-300))


def scaled(stimulus: Stimulus, factor: float) -> Stimulus:
    """``stimulus`` with every force multiplied by ``factor``."""
    return replace(stimulus, name=f"{stimulus.name} x{factor:g}",
                   forces={m: (factor * f[0], factor * f[1], factor * f[2])
                           for m, f in stimulus.forces.items()})
