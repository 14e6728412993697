"""What touches the skin's surface inside a sensor kernel: the per-step piece a world fills.

A sensor kernel (:mod:`skinhil.model.sensor`) adds, before each step of its mechanics, the
forces that the skin's state at the step's start draws from whatever touches it:
:func:`surface_forces`. Without a world (``touch`` None) the piece is nothing and compiles
away, so the plain and the scheduled blocks are the very kernels they would be without it.
The model knows no world (it sits below it): a world registers its own piece for its
``touch`` operands with :func:`numba.extending.overload`, as
:mod:`skinhil.world.touch` does for the contacts, and the kernel compiled for those operands
runs it.
"""

from __future__ import annotations

import numba
import numpy as np
from numba.extending import overload


def surface_forces(touch: tuple | None, step: int, t_s: float, dt_s: float, q: np.ndarray,
                   v: np.ndarray, out: np.ndarray) -> None:
    """Add what touches the skin at step ``step`` of a block (sensor time ``t_s``, s; step
    ``dt_s``, s) into ``out`` (3, n_slots) N by component and slot, from the displacements
    ``q`` (m) and velocities ``v`` (m/s) at the step's start, (3, n_slots) each. Compiled
    only (module docstring)."""
    raise NotImplementedError("surface_forces runs inside a compiled sensor kernel only")


@overload(surface_forces, inline="always")
def _untouched(touch, step, t_s, dt_s, q, v, out):  # type: ignore[no-untyped-def]
    # nothing touches: the piece compiles to nothing
    if isinstance(touch, numba.types.NoneType):
        def nothing(touch, step, t_s, dt_s, q, v, out):  # type: ignore[no-untyped-def]
            return None
        return nothing
    return None
