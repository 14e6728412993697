"""A sensor's mechanics and neurons on two threads: the neurons one block behind.

Within a block the neurons need the spring forces of the same steps, so on one thread a
block costs mechanics + neurons. The data flow one way, though (forces → springs → spikes,
nothing back), so two blocks can be in flight at once: while the calling thread steps the
mechanics over block ``k``, a worker thread steps the neurons over the spring forces of block
``k − 1``. A block then costs the larger of the two (plus a hand-over of tens of µs), for one
block of latency: the spikes of a block come out one call later. Both kernels release the
interpreter lock, so the two really run at once.

The same spikes as :meth:`skinhil.sensor.SkinSensor.advance`, block for block (same
arithmetic and the same noise draws, in the same order), one call late; the board uses this
with ``threads`` > 1 (:class:`firmware_sim.board.Board`) for skins of thousands of sensors,
where one core cannot keep real time.
"""

from __future__ import annotations

import logging
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from skinhil.sensor import SkinSensor

log = logging.getLogger(__name__)


class SensorPipeline:
    """Steps ``sensor``'s mechanics on the calling thread and its neurons (on
    ``sensor.threads`` threads of their own) one block behind, concurrently.

    ``spike_index`` counts the steps whose spikes have come out; ``sensor.step_index`` the
    steps the mechanics have taken (one block more once a block is in flight).
    """

    def __init__(self, sensor: SkinSensor) -> None:
        self.sensor = sensor
        self.spike_index = 0
        """Steps whose spikes have been returned; step k starts at ``k·sensor.dt_s``."""
        self._pending: np.ndarray | None = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="skinhil-neurons")

    @property
    def in_flight(self) -> int:
        """Steps whose spring forces are computed but whose spikes are not out yet."""
        return 0 if self._pending is None else len(self._pending)

    def advance(self, forces_n: np.ndarray) -> tuple[np.ndarray, int]:
        """Step the mechanics over ``forces_n`` ((n, n_masses, 3) N, one row per step) while
        the neurons step over the previous block.

        Returns the bool spikes (steps, n_springs) of the previous block and the index of its
        first step: the first call after a reset returns no steps.
        """
        sensor = self.sensor
        job: Future[np.ndarray] | None = None
        if self._pending is not None:
            job = self._worker.submit(sensor.neurons.step_block, self._pending, sensor.dt_s)
        try:
            springs = sensor.stepper.advance(forces_n)
        finally:
            done = self._collect(job)
        sensor.step_index += len(forces_n)
        self._pending = springs
        return done

    def flush(self) -> tuple[np.ndarray, int]:
        """Step the neurons over the block in flight (on the worker) and return its spikes
        and first step, as :meth:`advance` would have on its next call."""
        job = None
        if self._pending is not None:
            job = self._worker.submit(self.sensor.neurons.step_block, self._pending,
                                      self.sensor.dt_s)
        done = self._collect(job)
        self._pending = None
        return done

    def _collect(self, job: Future[np.ndarray] | None) -> tuple[np.ndarray, int]:
        first = self.spike_index
        if job is None:
            return np.zeros((0, self.sensor.model.n_springs), dtype=np.bool_), first
        spikes = job.result()
        self.spike_index += len(spikes)
        return spikes, first

    def reset(self) -> None:
        """Mechanics and membranes back to rest, time back to 0, nothing in flight."""
        self._pending = None
        self.sensor.reset()
        self.spike_index = 0

    def close(self) -> None:
        """Stop the worker thread (waits for a block in flight)."""
        self._worker.shutdown(wait=True)
