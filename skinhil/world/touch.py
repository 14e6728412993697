"""A skin sensor that touches a world: the contact computed inside the compiled step.

Per step ``k`` of a block (one compiled call per block): the schedule's stimulus forces, as
:meth:`skinhil.model.sensor.SkinSensor.advance_schedule` makes them; the contacts' forces
from the skin's state at the start of step ``k`` (:func:`skinhil.world.contact.contact_forces`),
added to the top layer's input of step ``k``; the mechanics' step ``k`` with that input held
over it. The neurons then step the block as without contact. So a contact's force enters
exactly where a stimulus's does, and a block without contacts gives the very same numbers.
The block is the model's own sensor kernel (:meth:`skinhil.model.sensor.SkinSensor.run_fused`)
with a :class:`Touch`: this module registers the contacts as its surface piece
(:mod:`skinhil.model.surface`).

Two mechanics can carry a force that depends on the state: the leapfrog (the linear
mechanics above 8x8, or ``linear_stepper="leapfrog"``) and the geometric mechanics; the exact
ZOH of the linear mechanics cannot (:meth:`skinhil.model.skin.SkinModel.regime_for`), and
``auto`` picks the leapfrog there. The neurons run on one thread with contact (``threads``
> 1 is refused).
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numba.extending import overload

from skinhil.errors import ConfigError
from skinhil.model.mechanics.geometric import GeometricMechanics
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.model.surface import surface_forces
from skinhil.world.contact import ContactOperands, ContactParams, ContactState, contact_forces
from skinhil.world.scene import Scene, World
from skinhil.world.truth import RAW_FIELDS, truth_records

IDLE_OFFSET_S = 1e300
"""Scene offset of a world that is not playing: every contact is before its start."""


class Touch(NamedTuple):
    """A world's operands of the sensor kernels' surface piece (:mod:`skinhil.model.surface`);
    a kernel takes it as a plain tuple of plain tuples (:meth:`TouchSensor.advance_schedule`)."""

    scene_offset_s: float
    """Sensor time (s) of scene time 0."""
    contacts: tuple
    """:attr:`skinhil.world.scene.World.operands` (:class:`ContactOperands`), plain."""
    state: tuple
    """:attr:`skinhil.world.scene.World.state` (:class:`ContactState`), plain."""
    truth: np.ndarray
    """The contacts' truth by step of the block (n_steps, n_contacts, RAW_FIELDS)."""


@overload(surface_forces, inline="always")
def _contacts(touch, step, t_s, dt_s, q, v, out):  # type: ignore[no-untyped-def]
    # a touch of the world: the contacts' forces on the state at the step's start, and
    # their truth at that step
    if isinstance(touch, numba.types.BaseTuple):
        def contacts(touch, step, t_s, dt_s, q, v, out):  # type: ignore[no-untyped-def]
            world = Touch(*touch)
            contact_forces(t_s - world.scene_offset_s, dt_s, q, v, out,
                           ContactOperands(*world.contacts), ContactState(*world.state),
                           world.truth[step])
        return contacts
    return None


class TouchSensor:
    """A :class:`SkinSensor` whose skin touches ``scene`` (module docstring).

    The scene plays from sensor time :attr:`scene_offset_s` (s); :meth:`start` (re)starts
    it, :meth:`stop` lifts every indenter. ``sensor`` must have a stepper that can carry
    the contact (``SkinSensor(..., state_forces=True)``)."""

    def __init__(self, sensor: SkinSensor, scene: Scene,
                 params: ContactParams | None = None) -> None:
        stepper = sensor.stepper
        if not isinstance(stepper, LeapfrogMechanics | GeometricMechanics):
            raise ConfigError("contact needs the leapfrog or the geometric mechanics: build "
                              "the sensor with state_forces=True")
        if sensor.threads != 1:
            raise ConfigError("contact runs the neurons on one thread: give --threads 1")
        self.sensor = sensor
        model = sensor.model
        self.params = params or ContactParams.for_skin(model.params.stiffness_n_per_m,
                                                       SkinParams().stiffness_n_per_m)
        self.params.check(sensor.dt_s, model.params.mass_kg)
        rows, cols = model.size
        n_top = rows * cols
        fixed = model.fixed[:n_top]
        index = np.where(fixed, -1, stepper.slots[:n_top])
        self.world = World(scene, index, model.positions[:n_top, :2], model.size,
                           model.params.spacing_m, self.params)
        self.scene_offset_s = IDLE_OFFSET_S

    @property
    def scene(self) -> Scene:
        """What touches the skin."""
        return self.world.scene

    def start(self, now_s: float) -> None:
        """Play the scene from sensor time ``now_s`` (s): nothing touching before it."""
        self.world.reset()
        self.scene_offset_s = float(now_s)

    def stop(self) -> None:
        """Lift every indenter from the next step on."""
        self.world.reset()
        self.scene_offset_s = IDLE_OFFSET_S

    def reset(self) -> None:
        """The sensor back to rest and time 0; the scene stopped."""
        self.sensor.reset()
        self.stop()

    def advance_schedule(self, schedule: Schedule, n_steps: int, t_offset_s: float = 0.0
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step ``n_steps`` under ``schedule`` (schedule time 0 at sensor time
        ``t_offset_s``) and the scene: spring forces (n, n_springs) N, bool spikes (n,
        n_springs) and the contacts' truth at every step (n, n_contacts,
        :data:`skinhil.world.truth.RAW_FIELDS`), SI units."""
        s = self.sensor
        s.check_schedule(schedule)
        truth = np.zeros((n_steps, len(self.scene.contacts), RAW_FIELDS))
        contacts, state = self.world.kernel_tuple
        touch = tuple(Touch(self.scene_offset_s, contacts, state, truth))
        springs, spikes = s.run_fused(n_steps, schedule=schedule, t_offset_s=t_offset_s,
                                      touch=touch)
        return springs, spikes, truth

    def truth_at(self, truth: np.ndarray, first_step: int, every: int) -> np.ndarray:
        """Truth records (:data:`skinhil.world.truth.TRUTH_DTYPE`) of the steps of a block
        (first step ``first_step``) that are multiples of ``every``: the state at the start
        of each tick of ``every`` steps."""
        k = np.arange(first_step, first_step + len(truth))
        pick = k % every == 0
        t_us = np.round(k[pick] * self.sensor.dt_s * 1e6).astype(np.int64)
        return truth_records(truth[pick], t_us)

