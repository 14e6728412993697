"""The model: stimuli → skin mechanics → spring forces → noisy Izhikevich neurons → spikes → PSP.

Geometry (:mod:`.geometry`), the skin and its three mechanics (:mod:`.skin`,
:mod:`.mechanics`), stimuli and their per-step timeline (:mod:`.stimuli`, :mod:`.timeline`),
the neurons and their noise (:mod:`.neurons`, :mod:`.rng`), the PSP kernel (:mod:`.psp`), the
sensor that steps skin and neurons block by block (:mod:`.sensor`, :mod:`.pipeline`), and
offline trials (:mod:`.trials`). Nothing here knows the board, the wire, the receiver or the
command line.
"""

import protocols.kernel_cache  # noqa: F401  (numba's cache keyed on the sources, before any kernel)
