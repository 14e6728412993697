"""The run's grasp scores from a board's held object and truth log, and as text."""

from __future__ import annotations

from typing import Any

from skinhil.plant.object import HeldObject
from skinhil.plant.scores import grasp_scores
from skinhil.world import TruthLog


def plant_scores(plant: HeldObject, truth: TruthLog) -> dict[str, Any]:
    """The score file's ``"grasp"``: :func:`grasp_scores` of the truth's held-object records,
    with the GRIP counters (accepted, refused by outcome) and the grip log."""
    held = truth.objects()
    grips = {"accepted": len(plant.log), **{f"refused_{k}": n for k, n in plant.refused.items()}}
    if held is None:
        return {"lifts": 0, "grips": grips}
    out = grasp_scores(held, plant.params, grips, plant.lifts)
    out["grip_log"] = [[e.token, e.arrival_us, e.applied_us, e.grip_n] for e in plant.log]
    return out


def _num(value: float | None, fmt: str) -> str:
    return "n/a" if value is None else format(value, fmt)


def grasp_text(scores: dict[str, Any]) -> str:
    """A few lines: the score, lifts held, dropped and broken, reaction latency, slip
    distance, grip economy, the GRIPs accepted and refused."""
    if not scores.get("lifts"):
        return "grasp: no lift scored"
    g = scores["grips"]
    lat = scores["reaction_latency_ms"]
    refused = sum(v for k, v in g.items() if k.startswith("refused_"))
    return (f"grasp: score {scores['score']:.2f}; {scores['held']}/{scores['lifts']} lifts "
            f"held ({100 * scores['held_fraction']:.0f} %), {scores['dropped']} dropped, "
            f"{scores['broken']} broken; "
            f"{scores['slips']} slipped, reaction latency median "
            f"{_num(lat['median'], '.0f')} ms over {lat['count']}; slip distance median "
            f"{_num(scores['slip_distance_mm']['median'], '.3f')} mm; grip economy "
            f"(safety margin) median {_num(scores['grip_economy']['median'], '.2f')}; "
            f"GRIPs received {g['accepted'] + refused}: {g['accepted']} accepted, {refused} "
            f"refused ({g.get('refused_busy', 0)} of them busy, before the object)")
