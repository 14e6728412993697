"""The held object's ground truth: one record per tick (the board keeps it in its TruthLog).

Grip and load are the set-points of that tick (the hand's grip, the object's load profile),
normal and tangential force and the slip state the contact's at the tick's start (as
:data:`skinhil.world.TRUTH_DTYPE`), slip distance and drop as they stand at the tick's end.
"""

from __future__ import annotations

import numpy as np

HELD_DTYPE = np.dtype([
    ("t_us", "<i8"), ("lift", "<u2"), ("held", "?"), ("dropped", "?"),
    ("grip_n", "<f8"), ("load_n", "<f8"), ("normal_n", "<f8"), ("tangential_n", "<f8"),
    ("slip", "u1"), ("slip_distance_mm", "<f8"), ("broken", "?"),
])
"""One tick of the held object. ``t_us``: board time (µs) of the tick's start; ``lift``: the
lift running (1-based; 0 between lifts); ``held``: the object is in the hand (a lift runs and
it has neither dropped nor broken); ``dropped``: this lift's object has dropped; ``grip_n``:
the grip set-point (N); ``load_n``: the object's tangential load (N, 0 between lifts); ``normal_n``,
``tangential_n``: the contact's forces on the skin (N); ``slip``: the contact's slip state
(:data:`skinhil.world.SLIP_STATES`); ``slip_distance_mm``: how far the object has slid on the
skin in this lift (mm); ``broken``: this lift's object has broken (a grip above its break
force)."""
