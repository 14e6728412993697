"""The sensing pipeline of one skin: mechanics and neurons stepped together at a fixed dt.

This is the model half of the sensor board: per block of steps, external forces (N) →
spring forces (N) → spikes. The board's real-time loop and the offline ``simulate`` command
both step it.
"""

from __future__ import annotations

import math

import numpy as np

from skinhil.neurons import IzhikevichParams, NeuronPopulation, raster_to_events
from skinhil.skin import SkinModel
from skinhil.stimuli import Schedule


class SkinSensor:
    """Skin mechanics plus one noisy Izhikevich neuron per spring, at step ``dt_s`` (s)."""

    def __init__(self, model: SkinModel | None = None, dt_s: float = 1e-4,
                 snr_db: float = math.inf, seed: int | None = None,
                 params: IzhikevichParams | None = None) -> None:
        self.model = model or SkinModel()
        self.dt_s = float(dt_s)
        self.stepper = self.model.stepper(dt_s)
        self.neurons = NeuronPopulation(self.model.n_springs, params, snr_db, seed)
        self.step_index = 0
        """Steps taken since the last reset; step k starts at ``k·dt_s``."""

    def reset(self) -> None:
        """Mechanics and membranes back to rest, time back to 0 (noise streams continue)."""
        self.stepper.reset()
        self.neurons.reset()
        self.step_index = 0

    def set_snr(self, snr_db: float) -> None:
        """Change the neuron noise level (dB; inf for none) from the next step on."""
        self.neurons.set_snr(snr_db)

    def advance(self, forces_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step ``len(forces_n)`` steps with external forces (n, 77, 3) N held per step.

        Returns the spring forces (n, 338) N at the start of each step and the bool spikes
        (n, 338) fired during each step.
        """
        springs = self.stepper.advance(forces_n)
        spikes = self.neurons.step_block(springs, self.dt_s)
        self.step_index += len(forces_n)
        return springs, spikes

    def advance_schedule(self, schedule: Schedule, n_steps: int,
                         t_offset_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Step ``n_steps`` under ``schedule`` (schedule time 0 at sensor time ``t_offset_s``)."""
        t = (self.step_index + np.arange(n_steps)) * self.dt_s - t_offset_s
        return self.advance(schedule.force_at(t))

    def events(self, spikes: np.ndarray, first_step: int) -> np.ndarray:
        """Events (µs timestamps) of a spike block whose first row is step ``first_step``."""
        return raster_to_events(spikes, self.dt_s, t0_us=int(round(first_step * self.dt_s * 1e6)))
