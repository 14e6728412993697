"""The emulated sensor board: real-time loop, event FIFO, link and host commands."""

import protocols.kernel_cache  # noqa: F401  (numba's cache keyed on the sources, before any kernel)
