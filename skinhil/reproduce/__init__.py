"""``skinhil reproduce``: the paper's figures and a report of which claims the model
reproduces, for both mechanics, from documented defaults (see docs/reproduce.md)."""

from skinhil.reproduce.compute import ReproduceConfig
from skinhil.reproduce.figures import FIGURES
from skinhil.reproduce.run import ReproduceOutcome, reproduce

__all__ = ["FIGURES", "ReproduceConfig", "ReproduceOutcome", "reproduce"]
