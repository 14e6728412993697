"""Scores of a run of lifts from the held object's truth (:data:`HELD_DTYPE`), per lift and
per run (docs/grasp.md "Scores").

Per lift: held or dropped; the largest slip distance; the slip onset (the first
tick in partial or gross slip while loaded); the reaction latency, from the first such tick
within the unannounced pull (from its start until :data:`PULL_REACH_S` after it has ramped
down) to the first tick whose grip is above the grip at that onset, counted only when the grip
was steady (unchanged) for :data:`STEADY_S` before it (None otherwise, or without an increase
before the object drops or the lift ends: a grip raised after the drop saves nothing; a grip
that moves all the time, or rises on a timetable, reacts to nothing); the grip
economy, the median safety margin ``(G/L − r)/(G/L)`` over the
lift's ticks while it is held with a load of at least half its weight (``r`` the slip ratio
1/mu_static: 0 grips at the slip ratio, 0.5 twice it; negative: below it).

Per run, ``score`` in [0, 1]: the lifts held and not broken, over the lifts (a grip too low
drops the object, one too high breaks it); ``broken_lifts``: the lifts whose object broke.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skinhil.plant.lifts import G_M_PER_S2, GraspParams, Lift

ONSET_SLIP = 2
"""The slip codes from which a slip starts: partial slip (the contact's edge slipping, what
the skin can feel before the object moves) or gross slip."""
STEADY_S = 0.05
"""How long (s) the grip must have stayed unchanged before a slip onset for a rise after it to
count as a reaction."""
PULL_REACH_S = 0.05
"""How long (s) after the pull has ramped down a slip onset still counts as the pull's."""


def _reaction_ms(r: np.ndarray, slipping: np.ndarray, pull_s: tuple[float, float]
                 ) -> float | None:
    """The reaction latency (ms) of one lift's records ``r`` (module docstring)."""
    since_us = r["t_us"] - r["t_us"][0]
    in_pull = (since_us >= pull_s[0] * 1e6) & (since_us <= (pull_s[1] + PULL_REACH_S) * 1e6)
    onset = np.flatnonzero(slipping & in_pull)
    if not onset.size:
        return None
    k = int(onset[0])
    before = (since_us >= since_us[k] - STEADY_S * 1e6) & (since_us <= since_us[k])
    if since_us[k] < STEADY_S * 1e6 or np.any(r["grip_n"][before] != r["grip_n"][k]):
        return None
    up = np.flatnonzero((r["grip_n"][k:] > r["grip_n"][k]) & ~r["dropped"][k:])
    if not up.size:
        return None
    return (int(r["t_us"][k + int(up[0])]) - int(r["t_us"][k])) / 1e3


def trial_scores(held: np.ndarray, params: GraspParams,
                 lifts: tuple[Lift, ...] | None = None) -> list[dict[str, Any]]:
    """One dict per lift present in ``held`` (:data:`HELD_DTYPE` records, time order); the
    lifts of a drawn run (``lifts``) give each its own weight and pull."""
    out = []
    for lift in np.unique(held["lift"][held["lift"] > 0]).tolist():
        r = held[held["lift"] == lift]
        spec = lifts[lift - 1] if lifts else None
        weight = params.weight_n if spec is None else spec.mass_kg * G_M_PER_S2
        loaded = r["load_n"] >= 0.5 * weight
        slipping = (r["slip"] >= ONSET_SLIP) & loaded & ~r["dropped"]
        onset = np.flatnonzero(slipping)
        onset_ms = None
        if onset.size:
            onset_ms = (int(r["t_us"][int(onset[0])]) - int(r["t_us"][0])) / 1e3
        latency = _reaction_ms(r, slipping, (params.pull_start_s(spec), params.pull_end_s(spec)))
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
                 grips: dict[str, int] | None = None,
                 lifts: tuple[Lift, ...] | None = None) -> dict[str, Any]:
    """The run's scores (the score file's ``"grasp"``): ``score``, counts, fractions and
    medians over the lifts, the lifts' own scores, and ``grips`` (the GRIP counters) when
    given; ``lifts``: a drawn run's lifts."""
    trials = trial_scores(held, params, lifts)
    n = len(trials)
    held_n = sum(t["held"] for t in trials)
    lifted = held[held["lift"] > 0]
    broken = sorted(set(lifted["lift"][lifted["broken"]].tolist()))
    won = sum(t["held"] and t["lift"] not in broken for t in trials)
    lat = [t["reaction_latency_ms"] for t in trials if t["reaction_latency_ms"] is not None]
    out: dict[str, Any] = {
        "score": won / n if n else None,
        "lifts": n, "held": held_n, "dropped": n - held_n,
        "broken": len(broken), "broken_lifts": broken,
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
