"""Scores that cannot be won without sensing (issue 41): scripted decoders that read no spike
answer the cases of ``tactile-v1`` and are scored by the board through the wire (ANSWER,
DECISION, GRIP encoded by the host's encoder, decoded by the board), each beside the random
answerer (``listen --answer --answer-with random``'s answerer on the receiver's onsets) and
the reference grip controller played on the same seed the same way.

The gamers and baselines are the roster's (``harness/gamer_roster.py``, which
``benchmarks/bench_gamers.py`` pools over seeds), played off the clock
(``harness/suite_play.py``: exact, every command at its tick); one gamer of each family goes
over a real pty against ``skinhil serve --suite`` too.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

import pytest
from conftest import PtyPair, PtyReader
from harness import gamer_roster as r
from harness import gamers as g
from harness.serve import ServeProcess
from harness.suite_play import Played

import protocols
from skinhil.plant import GraspParams
from skinhil.scoring import DecisionScoreboard
from skinhil.suites.tactile_v1 import VIBRATION_CLASSES_HZ

SEED = 1_000_003
"""The evaluation seed every gamer and baseline is scored on."""
OTHER_SEED = 1_000_001
"""The seed whose truth the replaying gamer answers (``serve --truth`` of that run)."""


def _gamer(name: str) -> Played:
    return r.GAMERS[name](SEED, OTHER_SEED)


def _random(case: str) -> Played:
    return r.random_answerer(case, SEED)


WINS = {
    "slip-0.2s-after-each-touch": "a SLIP at a delay after each touch-down near the end of "
                                  "the drawn stick lands in the slip window of most slips: "
                                  "the window cannot be narrower than the reference's slip "
                                  "latencies, and the stick's spread (0.2 s) is not much "
                                  "wider; this decoder senses touches, not slips",
}
"""Gamers that still beat the random answerer: holes of the rule that stay open (each
strict, so a fix of the rule shows as an unexpected pass)."""


@pytest.mark.parametrize("gamer", [pytest.param(
    name, marks=pytest.mark.xfail(reason=WINS[name], strict=True) if name in WINS else ())
    for name in r.GAMERS])
def test_a_gamer_scores_at_or_below_the_random_answerer(gamer: str) -> None:
    case = r.case_of(gamer)
    played = _gamer(gamer)
    score = played.score(case)
    random_score = _random(case).score(case)
    scored = played.task(case)
    # the board scored what the gamer sent: every answer landed in one counter
    outcomes = ("right", "wrong", "duplicates", "late", "false_alarms", "while_stopped")
    assert sum(scored[o] for o in outcomes) == scored.get("answers", scored.get("decisions"))
    assert score <= random_score, (
        f"{gamer} scored {score:.3f}, the random answerer {random_score:.3f}: {scored}")


CONSTANT_SEEDS = (SEED, 1_000_005, 1_000_007)
"""The seeds a constant class is played on: a constant and a random class meet only in
expectation (chance = 1 / classes)."""


def _chance_bound(trials: int, classes: int) -> float:
    """The score a random class reaches at most with 95 % confidence over ``trials`` trials
    of ``classes`` classes answered once each: the binomial quantile of chance, over the
    trials."""
    p, total, k = 1 / classes, 0.0, 0
    for k in range(trials + 1):
        total += math.comb(trials, k) * p ** k * (1 - p) ** (trials - k)
        if total >= 0.95:
            break
    return k / trials


@pytest.mark.parametrize("hz", (50.0, 300.0))
def test_a_constant_class_scores_no_more_than_chance_over_seeds(hz: float) -> None:
    """VIBRATION: a constant frequency at the response window's cadence, over
    :data:`CONSTANT_SEEDS`, within the random answerer's chance bound (a constant right more
    often than chance allows fails)."""
    played = [r.CONSTANT_CLASSES[f"vibration-constant-{hz:g}Hz"](s, OTHER_SEED)
              for s in CONSTANT_SEEDS]
    trials = sum(p.task("vibration")["trials"] for p in played)
    right = sum(p.task("vibration")["right"] for p in played)
    assert trials > 0 and sum(p.task("vibration")["answers"] for p in played) > 0
    bound = _chance_bound(trials, len(VIBRATION_CLASSES_HZ))
    assert sum(p.score("vibration") for p in played) / len(played) <= bound
    assert right / trials <= bound, f"{hz} Hz right on {right} of {trials} trials"


def test_the_reference_receiver_detects_the_slips_in_their_window() -> None:
    """The slip window and the charge of every unmatched SLIP leave the reference answerer
    (``listen --answer --answer-with reference``) a high slip score."""
    played = r.reference_answerer("slip", SEED)
    assert played.score("slip") >= 0.8, played.task("slip")


def test_an_answer_repeated_for_a_trial_voids_its_right_answer() -> None:
    """Several answers per onset: the hedges that were right count for nothing, each extra
    answer against the score."""
    s = _gamer("force-several-per-onset").task("force")
    assert s["duplicates"] >= 4 * s["matched"] and s["hedged"] == s["right"]
    assert s["score"] == 0.0


def test_a_silent_decoder_scores_zero_on_every_trial() -> None:
    s = _gamer("localisation-silent").task("localisation")
    assert s["answers"] == 0 and s["trials"] > 0 and s["score"] == 0.0
    assert s["misses"] + s["pending"] == s["trials"]


# -- the grip --------------------------------------------------------------------------------

def _gripped(name: str) -> Played:
    return r.GRIPPERS[name](SEED)


@pytest.mark.parametrize("name", list(r.GRIPPERS))
def test_a_blind_grip_wins_at_most_one_kind_of_object(name: str) -> None:
    grasp = _gripped(name).scores["grasp"]
    assert grasp["grips"]["accepted"] > 0
    assert sum(v for k, v in grasp["grips"].items() if k.startswith("refused_")) == 0
    assert grasp["score"] <= 0.5, grasp


@pytest.mark.parametrize("name", list(r.GRIPPERS))
def test_a_blind_grip_scores_well_below_the_reference_controller(name: str) -> None:
    reference = r.grasp_reference(SEED).score("grasp")
    assert _gripped(name).score("grasp") <= reference - r.GRASP_MARGIN


def test_the_maximum_grip_breaks_the_objects_and_the_score_file_says_so() -> None:
    grasp = _gripped("maximum").scores["grasp"]
    assert grasp["broken"] == grasp["lifts"] > 0 and grasp["score"] == 0.0
    assert grasp["broken_lifts"] == list(range(1, grasp["lifts"] + 1))
    assert all(t["peak_grip_n"] == GraspParams().max_grip_n for t in grasp["trials"])


# -- over a real pty -------------------------------------------------------------------------


def _over_pty(case: str, commands: list[tuple[float, Any]], tmp: Path) -> dict[str, Any]:
    """``skinhil serve --suite`` of :data:`SEED` on a pty, ``commands`` ((board time s,
    command) in order) written by the host's encoder as the board runs; the score file."""
    pair = PtyPair()
    reader = PtyReader(pair.master)
    score = tmp / "score.json"
    serve = ServeProcess("--suite", r.ref(case), "--seed", str(SEED), "--port", pair.path,
                         "--score", str(score), "--json")
    try:
        serve.wait_ready()
        encoder = protocols.SerialEncoder()
        t0 = time.monotonic()
        for at_s, cmd in commands:
            wait = at_s - (time.monotonic() - t0)
            if wait > 0:
                time.sleep(wait)
            pair.write(encoder.command(cmd))
            if serve.exited:
                break
        assert serve.wait(120) == 0, serve.stderr
    finally:
        serve.kill()
        reader.stop()
        pair.close()
    return json.loads(score.read_text(encoding="utf-8"))


def _timed(script: g.Script) -> list[tuple[float, Any]]:
    return [(k * 1e-3, c) for k in sorted(script) for c in script[k]]


def test_slip_every_10ms_over_a_pty_scores_no_more_than_random(tmp_path: Path) -> None:
    script = g.cadence(g.task_id("slip"), g.constant(()), 0.01, r.duration_s("slip", SEED))
    scores = _over_pty("slip", _timed(script), tmp_path)
    slip = scores["tasks"]["slip"]
    assert slip["answers"] >= 0.8 * sum(len(v) for v in script.values())
    assert slip["score"] <= _random("slip").score("slip")
    assert slip["hedged"] == slip["right"]


def test_the_maximum_grip_over_a_pty_breaks_the_objects(tmp_path: Path) -> None:
    top = GraspParams().max_grip_n
    steps = int((top - 0.3) / g.GRIP_STEP_N) + 1
    ramp = [(0.01 * (i + 1), protocols.Command(i + 1, protocols.CommandCode.GRIP,
                                               min(top, round(0.3 + g.GRIP_STEP_N * (i + 1), 6))))
            for i in range(steps)]  # one GRIP per 10 ms: two never share a tick
    scores = _over_pty("grasp", ramp, tmp_path)
    grasp = scores["grasp"]
    assert grasp["broken"] == grasp["lifts"] > 0 and grasp["score"] == 0.0


def test_classification_scores_by_the_same_rule() -> None:
    """A DECISION's headline: right alone wins its onset, a second DECISION voids it, each
    extra one is charged (SPEC §3.5.4)."""
    board = DecisionScoreboard(0.5)
    board.onset(3, 0)
    board.onset(5, 1_000_000)
    board.decision(3, 100_000)
    board.decision(5, 1_100_000)
    board.decision(5, 1_200_000)
    board.advance(2_000_000)
    s = board.summary()
    assert (s["right"], s["duplicates"], s["hedged"]) == (2, 1, 1)
    assert s["score"] == round((2 - 1) / (2 + 3 - 2), 6)
