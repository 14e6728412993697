"""Scores of a run of lifts from the held object's truth (:data:`HELD_DTYPE`), per lift and
per run (docs/grasp.md "Scores").

Per lift: held or dropped; the largest slip distance; the slip onset (the first tick in
partial or gross slip while loaded); the reaction latency, from the onset to the first tick
whose grip is above the grip at the onset (None without a slip, or without an increase before
the object drops or the lift ends: a grip raised after the drop saves nothing); the grip
economy, the median safety margin ``(G/L − r)/(G/L)`` over the
lift's ticks while it is held with a load of at least half its weight (``r`` the slip ratio
1/mu_static: 0 grips at the slip ratio, 0.5 twice it; negative: below it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skinhil.plant.lifts import GraspParams

ONSET_SLIP = 2
"""The slip codes from which a slip starts: partial slip (the contact's edge slipping, what
the skin can feel before the object moves) or gross slip."""


def trial_scores(held: np.ndarray, params: GraspParams) -> list[dict[str, Any]]:
    """One dict per lift present in ``held`` (:data:`HELD_DTYPE` records, time order)."""
    out = []
    for lift in np.unique(held["lift"][held["lift"] > 0]).tolist():
        r = held[held["lift"] == lift]
        loaded = r["load_n"] >= 0.5 * params.weight_n
        onset = np.flatnonzero((r["slip"] >= ONSET_SLIP) & loaded & ~r["dropped"])
        latency = None
        onset_ms = None
        if onset.size:
            k = int(onset[0])
            onset_ms = (int(r["t_us"][k]) - int(r["t_us"][0])) / 1e3
            up = np.flatnonzero((r["grip_n"][k:] > r["grip_n"][k]) & ~r["dropped"][k:])
            if up.size:
                latency = (int(r["t_us"][k + int(up[0])]) - int(r["t_us"][k])) / 1e3
        hold = loaded & r["held"]
        ratio = r["grip_n"][hold] / r["load_n"][hold]
        margin = (ratio - params.slip_ratio) / ratio
        out.append({
            "lift": int(lift), "held": not bool(r["dropped"][-1]),
            "slip_distance_mm": float(r["slip_distance_mm"].max()),
            "slip_onset_ms": onset_ms, "reaction_latency_ms": latency,
            "grip_economy": float(np.median(margin)) if margin.size else None,
            "peak_grip_n": float(r["grip_n"].max()),
        })
    return out


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def grasp_scores(held: np.ndarray, params: GraspParams,
                 grips: dict[str, int] | None = None) -> dict[str, Any]:
    """The run's scores (the score file's ``"grasp"``): counts, fractions and medians over
    the lifts, the lifts' own scores, and ``grips`` (the GRIP counters) when given."""
    trials = trial_scores(held, params)
    n = len(trials)
    held_n = sum(t["held"] for t in trials)
    lat = [t["reaction_latency_ms"] for t in trials if t["reaction_latency_ms"] is not None]
    out: dict[str, Any] = {
        "lifts": n, "held": held_n, "dropped": n - held_n,
        "held_fraction": held_n / n if n else None,
        "dropped_fraction": (n - held_n) / n if n else None,
        "slips": sum(t["slip_onset_ms"] is not None for t in trials),
        "reaction_latency_ms": {"median": _median(lat), "count": len(lat),
                                "max": max(lat) if lat else None},
        "slip_distance_mm": {"median": _median([t["slip_distance_mm"] for t in trials])},
        "grip_economy": {"median": _median([t["grip_economy"] for t in trials
                                            if t["grip_economy"] is not None])},
        "slip_ratio": params.slip_ratio, "weight_n": params.weight_n,
        "trials": trials,
    }
    if grips is not None:
        out["grips"] = grips
    return out
