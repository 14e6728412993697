"""The grasp scores of a lift from its truth (skinhil.plant.scores, docs/grasp.md "Scores")."""

from __future__ import annotations

import numpy as np

from skinhil.plant import GraspParams
from skinhil.plant.scores import STEADY_S, grasp_scores, trial_scores
from skinhil.plant.truth import HELD_DTYPE

PARAMS = GraspParams()
N_MS = 800
PULL_MS = int(round(PARAMS.pull_start_s() * 1e3))


def _lift(grip: dict[int, float], slip_ms: int, drop_ms: int | None = None,
          lift: int = 1) -> np.ndarray:
    """One loaded lift, a tick per ms: the grip takes each value of ``grip`` from its ms on,
    the contact slips from ``slip_ms``, the object drops at ``drop_ms``."""
    r = np.zeros(N_MS, dtype=HELD_DTYPE)
    r["t_us"] = np.arange(N_MS) * 1000
    r["lift"] = lift
    for ms, g in sorted(grip.items()):
        r["grip_n"][ms:] = g
    r["slip"][slip_ms:] = 2
    if drop_ms is not None:
        r["dropped"][drop_ms:] = True
    r["held"] = ~r["dropped"]
    r["load_n"] = PARAMS.weight_n
    return r


def test_the_reaction_latency_runs_from_the_pulls_slip_to_the_first_grip_increase() -> None:
    lift = _lift({0: 0.6, PULL_MS + 12: 0.9}, PULL_MS + 10)
    (score,) = trial_scores(lift, PARAMS)
    assert score["held"] and score["slip_onset_ms"] == PULL_MS + 10
    assert score["reaction_latency_ms"] == 2.0


def test_a_grip_raised_after_the_drop_is_no_reaction() -> None:
    lift = _lift({0: 0.6, PULL_MS + 15: 0.9}, PULL_MS + 10, drop_ms=PULL_MS + 12)
    (score,) = trial_scores(lift, PARAMS)
    assert not score["held"] and score["reaction_latency_ms"] is None


def test_a_grip_that_moved_just_before_the_slip_reacts_to_nothing() -> None:
    moved = PULL_MS + 10 - int(STEADY_S * 1e3) // 2
    lift = _lift({0: 0.6, moved: 0.7, PULL_MS + 12: 0.9}, PULL_MS + 10)
    (score,) = trial_scores(lift, PARAMS)
    assert score["slip_onset_ms"] == PULL_MS + 10 and score["reaction_latency_ms"] is None


def test_a_slip_outside_the_pull_is_no_perturbation() -> None:
    lift = _lift({0: 0.6, 202: 0.9}, 200)
    (score,) = trial_scores(lift, PARAMS)
    assert score["slip_onset_ms"] == 200.0 and score["reaction_latency_ms"] is None


def test_the_score_counts_lifts_held_and_not_broken() -> None:
    held = _lift({0: 0.6}, N_MS)
    broken = _lift({0: 0.6}, N_MS, lift=2)
    broken["broken"][300:] = True
    dropped = _lift({0: 0.6}, 400, drop_ms=450, lift=3)
    scores = grasp_scores(np.concatenate([held, broken, dropped]), PARAMS)
    assert scores["lifts"] == 3 and scores["broken"] == 1 and scores["dropped"] == 1
    assert scores["score"] == 1 / 3
