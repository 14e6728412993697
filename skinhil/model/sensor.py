"""The sensing pipeline of one skin: mechanics and neurons stepped together at a fixed dt.

This is the model half of the sensor board: per block of steps, external forces (N) →
spring forces (N) → spikes. The board's real-time loop and the offline ``simulate`` command
both step it.

With the modal linear stepper (linear mechanics without baseline tension on small meshes),
the leapfrog linear stepper (larger meshes) or the geometric mechanics (the default up to
10x10) a block, and under a schedule also its forces, is one compiled call that runs the
schedule's, the stepper's and the population's own kernels in turn: per-block Python work
would otherwise cost about as much as the arithmetic of a 1 ms block. The full state-space
linear stepper, and any stepper when the neurons run on several threads (``threads``), step
through ``SkinStepper.advance`` and ``NeuronPopulation.step_block``. Every step costs
O(springs) with the leapfrog and the geometric mechanics, and the neurons O(channels).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import format_size
from skinhil.model.mechanics.geometric import GeometricMechanics, GeometricOperands, rk4_step
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics, LeapfrogOperands, leapfrog_step
from skinhil.model.mechanics.linear import LinearMechanics, ModalOperands, modal_step
from skinhil.model.neurons import (
    MAX_CHANNELS,
    IzhikevichParams,
    NeuronPopulation,
    NoiseParams,
    fire,
    raster_to_events,
)
from skinhil.model.skin import SkinModel
from skinhil.model.stimuli import Schedule, add_schedule_forces
from skinhil.model.surface import surface_forces


@numba.njit(inline="always")
def _step_times(first_step: int, n_steps: int, dt_s: float,
                t_offset_s: float) -> np.ndarray:  # pragma: no cover - compiled
    # the schedule time (s) of each step of a block: step k starts at k·dt_s (s) of sensor
    # time, schedule time 0 at t_offset_s (s)
    return (first_step + np.arange(n_steps)) * dt_s - t_offset_s


@numba.njit(inline="always")
def _schedule_by_slot(first_step: int, dt_s: float, t_offset_s: float, slots: np.ndarray,
                      n_slots: int, springs: np.ndarray,
                      schedule: tuple) -> np.ndarray:  # pragma: no cover - compiled
    # the schedule's forces (N) by step, component and slot (a strip stepper's input, in
    # the precision of springs: the stepper's); schedule is Schedule.kernel_operands
    n_steps = springs.shape[0]
    forces = np.zeros((n_steps, 3, n_slots), dtype=springs.dtype)
    starts, onsets, ends, which, stim_onsets, stim_ends, taus, ptr, pushed, peaks = schedule
    add_schedule_forces(forces.transpose(0, 2, 1),
                        _step_times(first_step, n_steps, dt_s, t_offset_s), starts, onsets,
                        ends, which, stim_onsets, stim_ends, taus, ptr, slots[pushed], peaks)
    return forces


# The sensor kernels: one per mechanics, one compiled call per block. Per step k of the
# block: the input of step k (given, or the schedule's, made in the kernel), plus what
# touches the surface (skinhil.model.surface: nothing without a touch), then the mechanics'
# step; then the neurons over the block. Arguments: the block's first step, dt_s (s), the
# schedule's time offset t_offset_s (s), the forces (N; None under a schedule), the
# schedule's operands (Schedule.kernel_operands, or None), the touch (a world's operands,
# or None), the outputs springs (n_steps, n_springs) N and spikes (bool, same shape), the
# mechanics' kernel_tuple and tuple(NeuronPopulation.kernel_operands()). An absent part is
# None, and the kernel compiled for it is as if the part were not written.


@numba.njit(cache=True, nogil=True)
def _modal_sensor_kernel(first_step: int, dt_s: float, t_offset_s: float,
                         forces: Any, schedule: tuple | None,
                         springs: np.ndarray, spikes: np.ndarray, mechanics: tuple,
                         neurons: tuple) -> None:  # pragma: no cover - compiled
    # forces by mass (n, n_masses, 3); the exact ZOH carries no force of the state: no touch
    ops = ModalOperands(*mechanics)
    n_steps = springs.shape[0]
    if schedule is None:
        fs = forces
    else:
        fs = np.zeros((n_steps, ops.n_masses, 3))
        add_schedule_forces(fs, _step_times(first_step, n_steps, dt_s, t_offset_s), *schedule)
    flat = fs.reshape(n_steps, -1)
    for k in range(n_steps):
        modal_step(flat[k], springs[k], ops)
    fire(springs, dt_s, spikes, neurons)


@numba.njit(cache=True, nogil=True)
def _leapfrog_sensor_kernel(first_step: int, dt_s: float, t_offset_s: float,
                            forces: Any, schedule: tuple | None,
                            touch: tuple | None, springs: np.ndarray, spikes: np.ndarray,
                            mechanics: tuple, neurons: tuple) -> None:  # pragma: no cover
    # forces by slot (n, 3, n_slots); the surface sees the velocity at the step's start (w)
    ops = LeapfrogOperands(*mechanics)
    if schedule is None:
        fs = forces
    else:
        fs = _schedule_by_slot(first_step, dt_s, t_offset_s, ops.slots, ops.q.shape[1],
                               springs, schedule)
    for k in range(springs.shape[0]):
        surface_forces(touch, k, (first_step + k) * dt_s, dt_s, ops.q, ops.w, fs[k])
        leapfrog_step(fs[k], springs[k], dt_s, ops)
    fire(springs, dt_s, spikes, neurons)


@numba.njit(cache=True, nogil=True)
def _geometric_sensor_kernel(first_step: int, dt_s: float, t_offset_s: float,
                             forces: Any, schedule: tuple | None,
                             touch: tuple | None, springs: np.ndarray, spikes: np.ndarray,
                             mechanics: tuple, neurons: tuple) -> None:  # pragma: no cover
    # forces by slot (n, 3, n_slots)
    ops = GeometricOperands(*mechanics)
    if schedule is None:
        fs = forces
    else:
        fs = _schedule_by_slot(first_step, dt_s, t_offset_s, ops.slots, ops.q.shape[1],
                               springs, schedule)
    for k in range(springs.shape[0]):
        surface_forces(touch, k, (first_step + k) * dt_s, dt_s, ops.q, ops.v, fs[k])
        rk4_step(fs[k], springs[k], dt_s, ops)
    fire(springs, dt_s, spikes, neurons)


class SkinSensor:
    """Skin mechanics plus one noisy Izhikevich neuron per spring, at step ``dt_s`` (s);
    ``noise`` and ``threads`` as in :class:`~skinhil.model.neurons.NeuronPopulation`."""

    def __init__(self, model: SkinModel | None = None, dt_s: float = 1e-4,
                 snr_db: float = math.inf, seed: int | None = None,
                 params: IzhikevichParams | None = None,
                 noise: NoiseParams | None = None, threads: int = 1,
                 state_forces: bool = False) -> None:
        self.model = model or SkinModel()
        if self.model.n_springs > MAX_CHANNELS:
            raise ConfigError(f"a {format_size(self.model.size)} skin has "
                              f"{self.model.n_springs} sensors; event addresses are 16-bit "
                              f"(at most {MAX_CHANNELS} channels, a 63x63 skin): use a smaller "
                              "skin or several boards")
        self.dt_s = float(dt_s)
        self.stepper = self.model.stepper(dt_s, state_forces)
        """The mechanics; with ``state_forces`` one that can carry a contact
        (:meth:`SkinModel.stepper`)."""
        self.neurons = NeuronPopulation(self.model.n_springs, params, snr_db, seed, noise=noise,
                                        threads=threads)
        self.threads = self.neurons.threads
        """Threads the neurons of a block run on (the mechanics step on one)."""
        self.step_index = 0
        """Steps taken since the last reset; step k starts at ``k·dt_s``."""
        self.fused = self.threads == 1 and (
            isinstance(self.stepper, LeapfrogMechanics | GeometricMechanics)
            or isinstance(self.stepper, LinearMechanics) and self.stepper.modal)
        """Whether a block is one compiled call (:meth:`run_fused`): mechanics and neurons
        on one thread, any stepper but the linear one with a baseline tension."""
        self._checked: Schedule | None = None

    def reset(self) -> None:
        """Mechanics and membranes back to rest, time back to 0 (noise streams continue)."""
        self.stepper.reset()
        self.neurons.reset()
        self.step_index = 0

    def set_snr(self, snr_db: float) -> None:
        """Change the neuron noise level (dB; inf for none) from the next step on."""
        self.neurons.set_snr(snr_db)

    def advance(self, forces_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step ``len(forces_n)`` steps with external forces (n, n_masses, 3) N held per step.

        Returns the spring forces (n, n_springs) N at the start of each step and the bool
        spikes (n, n_springs) fired during each step.
        """
        if not self.fused:
            springs = self.stepper.advance(forces_n)
            spikes = self.neurons.step_block(springs, self.dt_s)
            self.step_index += len(forces_n)
            return springs, spikes
        stepper = self.stepper
        if isinstance(stepper, LeapfrogMechanics | GeometricMechanics):
            forces = stepper.by_slot(forces_n)
        else:
            forces = np.ascontiguousarray(forces_n, dtype=np.float64)
        return self.run_fused(len(forces), forces=forces)

    def advance_schedule(self, schedule: Schedule, n_steps: int,
                         t_offset_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Step ``n_steps`` under ``schedule`` (schedule time 0 at sensor time ``t_offset_s``)."""
        self.check_schedule(schedule)
        if not self.fused:
            t = (self.step_index + np.arange(n_steps)) * self.dt_s - t_offset_s
            return self.advance(schedule.force_at(t, self.model.size))
        return self.run_fused(n_steps, schedule=schedule, t_offset_s=t_offset_s)

    def check_schedule(self, schedule: Schedule) -> None:
        """:class:`ConfigError` unless ``schedule`` pushes masses of this skin (checked once
        per schedule)."""
        if schedule is not self._checked:
            self.model.check_schedule(schedule)
            self._checked = schedule

    def run_fused(self, n_steps: int, forces: np.ndarray | None = None,
                  schedule: Schedule | None = None, t_offset_s: float = 0.0,
                  touch: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Step ``n_steps`` in one compiled call (:attr:`fused` only): under ``forces`` (N,
        as the stepper reads them: by slot for a strip stepper, by mass for the modal one)
        or ``schedule`` (schedule time 0 at sensor time ``t_offset_s``, s), plus ``touch``,
        the operands of what touches the surface (:mod:`skinhil.model.surface`; not with
        the modal stepper). Returns the spring forces (n_steps, n_springs) N and the bool
        spikes."""
        if not self.fused:
            raise ConfigError("one compiled call per block runs the neurons on one thread, "
                              "after the leapfrog, the geometric or the modal mechanics: "
                              "step this sensor with advance()")
        springs, spikes = self._outputs(n_steps)
        stepper = self.stepper
        plan = None if schedule is None else schedule.kernel_operands
        neurons = tuple(self.neurons.kernel_operands())
        first, dt, offset = self.step_index, self.dt_s, float(t_offset_s)
        if isinstance(stepper, LeapfrogMechanics):
            _leapfrog_sensor_kernel(first, dt, offset, forces, plan, touch, springs, spikes,
                                    stepper.kernel_tuple, neurons)
        elif isinstance(stepper, GeometricMechanics):
            _geometric_sensor_kernel(first, dt, offset, forces, plan, touch, springs, spikes,
                                     stepper.kernel_tuple, neurons)
        elif (isinstance(stepper, LinearMechanics) and stepper.kernel_tuple is not None
              and touch is None):
            _modal_sensor_kernel(first, dt, offset, forces, plan, springs, spikes,
                                 stepper.kernel_tuple, neurons)
        else:
            raise ConfigError("a touch needs the leapfrog or the geometric mechanics: build "
                              "the sensor with state_forces=True")
        self.step_index += n_steps
        return springs, spikes

    def _outputs(self, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Fresh spring-force (N, in the stepper's precision) and bool spike arrays for a
        block, each (n_steps, n_springs)."""
        shape = (n_steps, self.model.n_springs)
        stepper = self.stepper
        dtype = stepper.dtype if isinstance(stepper, LeapfrogMechanics) else np.float64
        return np.empty(shape, dtype=dtype), np.empty(shape, dtype=np.bool_)

    def events(self, spikes: np.ndarray, first_step: int) -> np.ndarray:
        """Events (µs timestamps) of a spike block whose first row is step ``first_step``."""
        return raster_to_events(spikes, self.dt_s, t0_us=int(round(first_step * self.dt_s * 1e6)))
