"""A skin sensor that touches a world: the contact computed inside the compiled step.

Per step ``k`` of a block (one compiled call per block): the schedule's stimulus forces, as
:meth:`skinhil.model.sensor.SkinSensor.advance_schedule` makes them; the contacts' forces
from the skin's state at the start of step ``k`` (:func:`skinhil.world.contact.contact_forces`),
added to the top layer's input of step ``k``; the mechanics' step ``k`` with that input held
over it. The neurons then step the block as without contact. So a contact's force enters
exactly where a stimulus's does, and a block without contacts gives the very same numbers.

Two mechanics can carry a force that depends on the state: the leapfrog (the linear
mechanics above 8x8, or ``linear_stepper="leapfrog"``) and the geometric mechanics; the exact
ZOH of the linear mechanics cannot (:meth:`skinhil.model.skin.SkinModel.regime_for`), and
``auto`` picks the leapfrog there. The neurons run on one thread with contact (``threads``
> 1 is refused).
"""

from __future__ import annotations

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.mechanics.geometric import GeometricMechanics, rk4_step
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics, leapfrog_kernel
from skinhil.model.neurons import _izhikevich_kernel
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinParams
from skinhil.model.stimuli import Schedule, add_schedule_forces
from skinhil.world.contact import ContactParams, contact_forces
from skinhil.world.scene import Scene, World
from skinhil.world.truth import RAW_FIELDS, truth_records

IDLE_OFFSET_S = 1e300
"""Scene offset of a world that is not playing: every contact is before its start."""


@numba.njit(cache=True, nogil=True, inline="always")
def _step_times_and_schedule_forces(first_step, dt, t_offset, slots, n_slots, springs,
                                    schedule):  # pragma: no cover - compiled
    # each step's sensor time (s) and the schedule's forces (N) by step, component and slot
    # in the precision of springs (the stepper's), as the schedule's sensor kernels make
    # them; inlined into each touch kernel (Numba IR), so each compiles as if written there
    n_steps = springs.shape[0]
    t = (first_step + np.arange(n_steps)) * dt
    forces = np.zeros((n_steps, 3, n_slots), dtype=springs.dtype)
    starts, onsets, ends, which, stim_onsets, stim_ends, taus, ptr, pushed, peaks = schedule
    add_schedule_forces(forces.transpose(0, 2, 1), t - t_offset, starts, onsets, ends, which,
                        stim_onsets, stim_ends, taus, ptr, slots[pushed], peaks)
    return t, forces


@numba.njit(cache=True, nogil=True)
def _leapfrog_touch_kernel(first_step, dt, t_offset, scene_offset, slots, n_slots, springs,
                           spikes, schedule, substeps, mechanics, neurons, operands, state,
                           truth):  # pragma: no cover - compiled
    # the schedule's forces by slot (as _scheduled_leapfrog_sensor_kernel), then per step the
    # contact on the state at its start and one leapfrog step; then the neurons
    n_steps = springs.shape[0]
    t, forces = _step_times_and_schedule_forces(first_step, dt, t_offset, slots, n_slots,
                                                springs, schedule)
    q = mechanics[12]
    w = mechanics[14]
    for k in range(n_steps):
        contact_forces(t[k] - scene_offset, dt, q, w, forces[k], operands, state, truth[k])
        leapfrog_kernel(forces[k:k + 1], springs[k:k + 1], dt, substeps, *mechanics)
    n = springs.shape[1]
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt * 1e3,
                       spikes.reshape(n_steps, 1, n), *neurons)


@numba.njit(cache=True, nogil=True)
def _geometric_touch_kernel(first_step, dt, t_offset, scene_offset, slots, n_slots, springs,
                            spikes, schedule, mechanics, neurons, operands, state,
                            truth):  # pragma: no cover - compiled
    # the schedule's forces by slot (as _scheduled_geometric_sensor_kernel), then per step the
    # contact on the state at its start and one RK4 step of the geometric mechanics; then
    # the neurons
    n_steps = springs.shape[0]
    t, forces = _step_times_and_schedule_forces(first_step, dt, t_offset, slots, n_slots,
                                                springs, schedule)
    q = mechanics[13]
    v = mechanics[14]
    for k in range(n_steps):
        contact_forces(t[k] - scene_offset, dt, q, v, forces[k], operands, state, truth[k])
        rk4_step(forces[k], springs[k], dt, *mechanics)
    n = springs.shape[1]
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt * 1e3,
                       spikes.reshape(n_steps, 1, n), *neurons)


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
        self._checked: Schedule | None = None

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
        if schedule is not self._checked:
            s.model.check_schedule(schedule)
            self._checked = schedule
        stepper = s.stepper
        truth = np.zeros((n_steps, len(self.scene.contacts), RAW_FIELDS))
        shape = (n_steps, s.model.n_springs)
        spikes = np.empty(shape, dtype=np.bool_)
        if isinstance(stepper, LeapfrogMechanics):
            springs = np.empty(shape, dtype=stepper.dtype)
            _leapfrog_touch_kernel(s.step_index, s.dt_s, float(t_offset_s),
                                   self.scene_offset_s, stepper.slots, stepper.state.shape[2],
                                   springs, spikes, schedule.kernel_operands, stepper.substeps,
                                   stepper.operands, s.neurons.kernel_operands(),
                                   self.world.operands, self.world.state, truth)
        else:
            assert isinstance(stepper, GeometricMechanics)
            springs = np.empty(shape)
            _geometric_touch_kernel(
                s.step_index, s.dt_s, float(t_offset_s), self.scene_offset_s, stepper.slots,
                stepper.state.shape[2], springs, spikes, schedule.kernel_operands,
                stepper.operands, s.neurons.kernel_operands(), self.world.operands,
                self.world.state, truth)
        s.step_index += n_steps
        return springs, spikes, truth

    def truth_at(self, truth: np.ndarray, first_step: int, every: int) -> np.ndarray:
        """Truth records (:data:`skinhil.world.truth.TRUTH_DTYPE`) of the steps of a block
        (first step ``first_step``) that are multiples of ``every``: the state at the start
        of each tick of ``every`` steps."""
        k = np.arange(first_step, first_step + len(truth))
        pick = k % every == 0
        t_us = np.round(k[pick] * self.sensor.dt_s * 1e6).astype(np.int64)
        return truth_records(truth[pick], t_us)

