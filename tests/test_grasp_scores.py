"""The grasp scores of a lift from its truth (skinhil.plant.scores, docs/grasp.md "Scores")."""

from __future__ import annotations

import numpy as np

from skinhil.plant import GraspParams
from skinhil.plant.scores import trial_scores
from skinhil.plant.truth import HELD_DTYPE

PARAMS = GraspParams()


def _lift(grip_n: list[float], slip: list[int], dropped: list[bool]) -> np.ndarray:
    """One loaded lift, a tick per ms."""
    r = np.zeros(len(grip_n), dtype=HELD_DTYPE)
    r["t_us"] = np.arange(len(grip_n)) * 1000
    r["lift"] = 1
    r["grip_n"], r["slip"], r["dropped"] = grip_n, slip, dropped
    r["held"] = ~r["dropped"]
    r["load_n"] = PARAMS.weight_n
    return r


def test_the_reaction_latency_runs_from_the_slip_onset_to_the_first_grip_increase() -> None:
    lift = _lift([0.6, 0.6, 0.6, 0.6, 0.9, 0.9], [0, 0, 2, 2, 1, 0], [False] * 6)
    (score,) = trial_scores(lift, PARAMS)
    assert score["held"] and score["slip_onset_ms"] == 2.0
    assert score["reaction_latency_ms"] == 2.0


def test_a_grip_raised_after_the_drop_is_no_reaction() -> None:
    lift = _lift([0.6, 0.6, 0.6, 0.6, 0.9, 0.9], [0, 0, 2, 3, 3, 3],
                 [False, False, False, True, True, True])
    (score,) = trial_scores(lift, PARAMS)
    assert not score["held"] and score["slip_onset_ms"] == 2.0
    assert score["reaction_latency_ms"] is None
