"""The world the skin touches: rigid indenters on trajectories, penalty contact and Coulomb
friction on the top layer, computed inside the compiled step, and the ground truth of every
contact (docs/contact.md).

It sits above the model (it steps the model's mechanics kernels with its forces added; the
model never imports it) and below the board, which plays scenarios and keeps the truth.
"""

from skinhil.world.contact import ContactParams
from skinhil.world.indenters import SHAPES, Indenter
from skinhil.world.scene import Contact, Scene, World
from skinhil.world.touch import TouchSensor
from skinhil.world.trajectory import Trajectory
from skinhil.world.truth import SLIP_STATES, TRUTH_DTYPE, TruthLog, truth_records

__all__ = ["SHAPES", "SLIP_STATES", "TRUTH_DTYPE", "Contact", "ContactParams", "Indenter",
           "Scene", "Trajectory", "TouchSensor", "TruthLog", "World", "truth_records"]
