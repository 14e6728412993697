"""A sensor's mechanics and neurons on two threads: the neurons two blocks behind.

Within a block the neurons need the spring forces of the same steps, so on one thread a
block costs mechanics + neurons. The data flow one way, though (forces → springs → spikes,
nothing back), so blocks can be in flight at once: while the calling thread steps the
mechanics over block ``k`` (and, in a board, publishes what came out), a worker thread steps
the neurons over block ``k − 1``; the call returns the spikes of block ``k − 2``, which the
worker finished during the previous call and the time after it. The calling thread never
waits for the worker unless the neurons take longer than a block, so a block costs the larger
of the two stages, not their sum, for two blocks of latency. Both kernels release the
interpreter lock, so the two really run at once.

The same spikes as :meth:`skinhil.model.sensor.SkinSensor.advance`, block for block (same
arithmetic and the same noise draws, in the same order), two calls late; a change of the
noise level (:meth:`SensorPipeline.set_snr`) reaches the first block whose neurons start
after it. The board uses this with ``threads`` > 1 (:class:`firmware_sim.board.Board`) for
skins of thousands of sensors, where one core cannot keep real time.
"""

from __future__ import annotations

from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from skinhil.model.neurons import check_snr_db
from skinhil.model.sensor import SkinSensor


class SensorPipeline:
    """Steps ``sensor``'s mechanics on the calling thread and its neurons (on
    ``sensor.threads`` threads of their own) two blocks behind, concurrently.

    ``spike_index`` counts the steps whose spikes have come out; ``sensor.step_index`` the
    steps the mechanics have taken (``in_flight`` more). :meth:`flush` before starting or
    stopping ``tracemalloc``: CPython crashes when tracing stops while the worker allocates.
    """

    def __init__(self, sensor: SkinSensor) -> None:
        self.sensor = sensor
        self.spike_index = 0
        """Steps whose spikes have been returned; step k starts at ``k·sensor.dt_s``."""
        self._running: Future[np.ndarray] | None = None
        self._running_steps = 0
        self._queued: np.ndarray | None = None
        self._snr_db: float | None = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="skinhil-neurons")

    @property
    def in_flight(self) -> int:
        """Steps whose spring forces are computed but whose spikes are not out yet."""
        return self._running_steps + (0 if self._queued is None else len(self._queued))

    def advance(self, forces_n: np.ndarray) -> tuple[np.ndarray, int]:
        """Step the mechanics over ``forces_n`` ((n, n_masses, 3) N, one row per step) while
        the neurons step over the block before.

        Returns the bool spikes (steps, n_springs) of the block two calls back and the index
        of its first step: the first two calls after a reset return no steps.
        """
        done = self._take()
        self._start()
        springs = self.sensor.stepper.advance(forces_n)
        self.sensor.step_index += len(forces_n)
        self._queued = springs
        return done

    def flush(self) -> tuple[np.ndarray, int]:
        """The spikes of every block in flight (their steps in order) and the first step's
        index, as the next calls of :meth:`advance` would have returned them."""
        first = self.spike_index
        out = [self._take()[0]]
        self._start()
        out.append(self._take()[0])
        return np.concatenate(out), first

    def set_snr(self, snr_db: float) -> None:
        """Change the noise level (dB; inf for none) from the next block whose neurons start
        on (the worker may be reading the level of the block it runs: change it here, not
        through the sensor)."""
        check_snr_db(snr_db)
        self._snr_db = snr_db

    def _start(self) -> None:
        """The neurons start on the queued block, on the worker (idle now)."""
        if self._snr_db is not None:
            self.sensor.set_snr(self._snr_db)
            self._snr_db = None
        if self._queued is not None:
            self._running = self._worker.submit(self.sensor.neurons.step_block, self._queued,
                                                self.sensor.dt_s)
            self._running_steps = len(self._queued)
            self._queued = None

    def _take(self) -> tuple[np.ndarray, int]:
        """The running block's spikes (waits for them) and its first step; none if idle."""
        first = self.spike_index
        job, self._running, self._running_steps = self._running, None, 0
        if job is None:
            return np.zeros((0, self.sensor.model.n_springs), dtype=np.bool_), first
        spikes = job.result()
        self.spike_index += len(spikes)
        return spikes, first

    def reset(self) -> None:
        """Mechanics and membranes back to rest, time back to 0, nothing in flight."""
        if self._running is not None:
            self._running.result()
        self._running, self._running_steps, self._queued = None, 0, None
        self.sensor.reset()
        self.spike_index = 0

    def close(self) -> None:
        """Stop the worker thread (waits for a block in flight)."""
        self._worker.shutdown(wait=True)
