"""A held object: pressed onto the skin by a grip, pulled by its load, held or dropped
(docs/grasp.md).

The plant sits on the world's contact model (one force-controlled flat contact per lift: its
normal load is the grip, its tangential load the object's), above the world and below the
board, which runs it each tick, takes GRIP commands for it and keeps its truth.
"""

from skinhil.plant.lifts import GraspParams, lift_scene, lifts_duration_s
from skinhil.plant.object import HeldObject
from skinhil.plant.scores import grasp_scores, trial_scores
from skinhil.plant.truth import HELD_DTYPE

__all__ = ["HELD_DTYPE", "GraspParams", "HeldObject", "grasp_scores", "lift_scene",
           "lifts_duration_s", "trial_scores"]
