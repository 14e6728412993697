"""Suites: versioned sets of cases whose trials come from the seed (docs/suites.md).

A case is data and a generator: a seed becomes a scenario (the world's contacts, the
stimuli, the held objects) and the tasks it poses. The board plays what it is given and
never knows suites; the command line turns ``--suite SUITE:CASE --seed N`` into what the
board takes.
"""

from skinhil.suites.case import Case, PosedTask, Suite, Trials
from skinhil.suites.registry import SUITES, case_ref, suite, suite_trials

__all__ = ["SUITES", "Case", "PosedTask", "Suite", "Trials", "case_ref", "suite",
           "suite_trials"]
