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

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import format_size
from skinhil.model.mechanics.geometric import GeometricMechanics, GeometricOperands, rk4_kernel
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics, LeapfrogOperands, leapfrog_kernel
from skinhil.model.mechanics.linear import LinearMechanics, ModalOperands, _advance_modal_kernel
from skinhil.model.neurons import (
    MAX_CHANNELS,
    IzhikevichParams,
    KernelOperands,
    NeuronPopulation,
    NoiseParams,
    _izhikevich_kernel,
    raster_to_events,
)
from skinhil.model.skin import SkinModel
from skinhil.model.stimuli import Schedule, ScheduleOperands, add_schedule_forces


@numba.njit(cache=True)
def _modal_sensor_kernel(forces: np.ndarray, springs: np.ndarray, spikes: np.ndarray,
                         dt_s: float, mechanics: ModalOperands,
                         neurons: KernelOperands) -> None:  # pragma: no cover - compiled
    # forces (n, n_masses, 3) N → springs (n, n_springs) N → spikes over steps of dt_s (s);
    # mechanics is LinearMechanics.modal_operands, neurons NeuronPopulation.kernel_operands()
    _advance_modal_kernel(forces, springs, *mechanics)
    n_steps, n = springs.shape
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt_s * 1e3,
                       spikes.reshape(n_steps, 1, n), *neurons)


@numba.njit(cache=True)
def _scheduled_modal_sensor_kernel(
        first_step: int, dt_s: float, t_offset_s: float, n_masses: int, springs: np.ndarray,
        spikes: np.ndarray, schedule: ScheduleOperands, mechanics: ModalOperands,
        neurons: KernelOperands) -> None:  # pragma: no cover - compiled
    # the schedule's forces (N) for steps first_step.. of dt_s (s), schedule time 0 at
    # t_offset_s (s), then _modal_sensor_kernel; schedule is Schedule.kernel_operands
    n_steps = springs.shape[0]
    t = (first_step + np.arange(n_steps)) * dt_s - t_offset_s
    forces = np.zeros((n_steps, n_masses, 3))
    add_schedule_forces(forces, t, *schedule)
    _modal_sensor_kernel(forces, springs, spikes, dt_s, mechanics, neurons)


@numba.njit(cache=True)
def _leapfrog_sensor_kernel(forces: np.ndarray, springs: np.ndarray, spikes: np.ndarray,
                            dt_s: float, substeps: int, mechanics: LeapfrogOperands,
                            neurons: KernelOperands) -> None:  # pragma: no cover - compiled
    # forces (n, 3, n_slots) N by slot → springs (n, n_springs) N → spikes over steps
    # of dt_s (s); mechanics is LeapfrogMechanics.operands, neurons
    # NeuronPopulation.kernel_operands()
    leapfrog_kernel(forces, springs, dt_s, substeps, *mechanics)
    n_steps, n = springs.shape
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt_s * 1e3,
                       spikes.reshape(n_steps, 1, n), *neurons)


@numba.njit(cache=True)
def _scheduled_leapfrog_sensor_kernel(
        first_step: int, dt_s: float, t_offset_s: float, slots: np.ndarray, n_slots: int,
        springs: np.ndarray, spikes: np.ndarray, schedule: ScheduleOperands, substeps: int,
        mechanics: LeapfrogOperands, neurons: KernelOperands) -> None:  # pragma: no cover
    # the schedule's forces (N) for steps first_step.. of dt_s (s), schedule time 0 at
    # t_offset_s (s), on the masses' slots (LeapfrogMechanics.slots), then
    # _leapfrog_sensor_kernel; schedule is Schedule.kernel_operands
    n_steps = springs.shape[0]
    t = (first_step + np.arange(n_steps)) * dt_s - t_offset_s
    forces = np.zeros((n_steps, 3, n_slots), dtype=springs.dtype)  # the stepper's precision
    starts, onsets, ends, which, stim_onsets, stim_ends, taus, ptr, pushed, peaks = schedule
    add_schedule_forces(forces.transpose(0, 2, 1), t, starts, onsets, ends, which,
                        stim_onsets, stim_ends, taus, ptr, slots[pushed], peaks)
    _leapfrog_sensor_kernel(forces, springs, spikes, dt_s, substeps, mechanics, neurons)


@numba.njit(cache=True)
def _geometric_sensor_kernel(forces: np.ndarray, springs: np.ndarray, spikes: np.ndarray,
                             dt_s: float, mechanics: GeometricOperands,
                             neurons: KernelOperands) -> None:  # pragma: no cover - compiled
    # forces (n, 3, n_slots) N by slot → springs (n, n_springs) N → spikes over steps
    # of dt_s (s); mechanics is GeometricMechanics.operands, neurons
    # NeuronPopulation.kernel_operands()
    rk4_kernel(forces, springs, dt_s, *mechanics)
    n_steps, n = springs.shape
    _izhikevich_kernel(springs.reshape(n_steps, 1, n), dt_s * 1e3,
                       spikes.reshape(n_steps, 1, n), *neurons)


@numba.njit(cache=True)
def _scheduled_geometric_sensor_kernel(
        first_step: int, dt_s: float, t_offset_s: float, slots: np.ndarray, n_slots: int,
        springs: np.ndarray, spikes: np.ndarray, schedule: ScheduleOperands,
        mechanics: GeometricOperands, neurons: KernelOperands) -> None:  # pragma: no cover
    # the schedule's forces (N) for steps first_step.. of dt_s (s), schedule time 0 at
    # t_offset_s (s), on the masses' slots (GeometricMechanics.slots), then
    # _geometric_sensor_kernel; schedule is Schedule.kernel_operands
    n_steps = springs.shape[0]
    t = (first_step + np.arange(n_steps)) * dt_s - t_offset_s
    forces = np.zeros((n_steps, 3, n_slots))
    starts, onsets, ends, which, stim_onsets, stim_ends, taus, ptr, pushed, peaks = schedule
    add_schedule_forces(forces.transpose(0, 2, 1), t, starts, onsets, ends, which,
                        stim_onsets, stim_ends, taus, ptr, slots[pushed], peaks)
    _geometric_sensor_kernel(forces, springs, spikes, dt_s, mechanics, neurons)


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
        fused = self.threads == 1  # one compiled call per block; else stepper, then neurons
        self._modal = (self.stepper.modal_operands
                       if fused and isinstance(self.stepper, LinearMechanics) else None)
        self._leapfrog = (self.stepper if fused and isinstance(self.stepper, LeapfrogMechanics)
                          else None)
        self._geometric = (self.stepper
                           if fused and isinstance(self.stepper, GeometricMechanics) else None)
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
        if self._modal is not None:
            springs, spikes = self._advance_modal(forces_n)
        elif self._leapfrog is not None:
            forces = self._leapfrog.by_slot(forces_n)
            springs, spikes = self._outputs(forces.shape[0])
            _leapfrog_sensor_kernel(forces, springs, spikes, self.dt_s,
                                    self._leapfrog.substeps, self._leapfrog.operands,
                                    self.neurons.kernel_operands())
        elif self._geometric is not None:
            forces = self._geometric.by_slot(forces_n)
            springs, spikes = self._outputs(forces.shape[0])
            _geometric_sensor_kernel(forces, springs, spikes, self.dt_s,
                                     self._geometric.operands, self.neurons.kernel_operands())
        else:
            springs = self.stepper.advance(forces_n)
            spikes = self.neurons.step_block(springs, self.dt_s)
        self.step_index += len(forces_n)
        return springs, spikes

    def _advance_modal(self, forces_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`advance`'s mechanics and neurons in one compiled call (modal stepper)."""
        assert self._modal is not None
        forces = np.ascontiguousarray(forces_n, dtype=np.float64)
        springs, spikes = self._outputs(forces.shape[0])
        _modal_sensor_kernel(forces, springs, spikes, self.dt_s, self._modal,
                             self.neurons.kernel_operands())
        return springs, spikes

    def advance_schedule(self, schedule: Schedule, n_steps: int,
                         t_offset_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Step ``n_steps`` under ``schedule`` (schedule time 0 at sensor time ``t_offset_s``)."""
        if schedule is not self._checked:
            self.model.check_schedule(schedule)
            self._checked = schedule
        if self._modal is None and self._leapfrog is None and self._geometric is None:
            t = (self.step_index + np.arange(n_steps)) * self.dt_s - t_offset_s
            return self.advance(schedule.force_at(t, self.model.size))
        springs, spikes = self._outputs(n_steps)
        if self._leapfrog is not None:
            _scheduled_leapfrog_sensor_kernel(
                self.step_index, self.dt_s, float(t_offset_s), self._leapfrog.slots,
                self._leapfrog.state.shape[2], springs, spikes, schedule.kernel_operands,
                self._leapfrog.substeps,
                self._leapfrog.operands, self.neurons.kernel_operands())
        elif self._geometric is not None:
            _scheduled_geometric_sensor_kernel(
                self.step_index, self.dt_s, float(t_offset_s), self._geometric.slots,
                self._geometric.state.shape[2], springs, spikes, schedule.kernel_operands,
                self._geometric.operands, self.neurons.kernel_operands())
        else:
            assert self._modal is not None
            _scheduled_modal_sensor_kernel(self.step_index, self.dt_s, float(t_offset_s),
                                           self.model.n_masses, springs, spikes,
                                           schedule.kernel_operands, self._modal,
                                           self.neurons.kernel_operands())
        self.step_index += n_steps
        return springs, spikes

    def _outputs(self, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Fresh spring-force (N, in the stepper's precision) and bool spike arrays for a
        block, each (n_steps, n_springs)."""
        shape = (n_steps, self.model.n_springs)
        dtype = np.float64 if self._leapfrog is None else self._leapfrog.dtype
        return np.empty(shape, dtype=dtype), np.empty(shape, dtype=np.bool_)

    def events(self, spikes: np.ndarray, first_step: int) -> np.ndarray:
        """Events (µs timestamps) of a spike block whose first row is step ``first_step``."""
        return raster_to_events(spikes, self.dt_s, t0_us=int(round(first_step * self.dt_s * 1e6)))
