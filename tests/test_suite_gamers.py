"""Scores that cannot be won without sensing (issue 41): scripted decoders that read no spike
answer the cases of ``tactile-v1`` and are scored by the board through the wire (ANSWER,
DECISION, GRIP encoded by the host's encoder, decoded by the board), each beside the random
answerer (``listen --answer --answer-with random``'s answerer on the receiver's onsets) and
the reference grip controller played on the same seed the same way.

The cases are played off the clock (``harness/suite_play.py``: exact, every command at its
tick); one gamer of each family goes over a real pty against ``skinhil serve --suite`` too.
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from conftest import PtyPair, PtyReader
from harness import gamers as g
from harness.serve import ServeProcess
from harness.suite_play import SNR_DB, Played, play_case, receiver_with, tick_of

import protocols
from skinhil.cli.demo_grasp import readout_training_runs
from skinhil.plant import GraspParams
from skinhil.receiver.answer import DecisionAnswerer
from skinhil.receiver.grip_loop import GripLoop
from skinhil.receiver.grip_reflex import GripController, LoadReadout, SlipReflex
from skinhil.receiver.grip_training import SUITE_TRAINING_GRIPS_N, fit_readout
from skinhil.receiver.task_answer import TaskAnswerer
from skinhil.scoring import DecisionScoreboard
from skinhil.suites import suite_trials
from skinhil.suites.tactile_v1 import VIBRATION_CLASSES_HZ

SEED = 1_000_003
"""The evaluation seed every gamer and baseline is scored on."""
OTHER_SEED = 1_000_001
"""The seed whose truth the replaying gamer answers (``serve --truth`` of that run)."""
SUITE = "tactile-v1"
CADENCE_S = 0.5
"""The constant answerers' period (s): the response window, about one answer per trial."""
SPAM_S = 0.005
"""The spammers' period (s)."""


def _ref(case: str) -> str:
    return f"{SUITE}:{case}"


def _duration_s(case: str) -> float:
    return suite_trials(_ref(case), SEED).duration_s


@cache
def _silent(case: str, seed: int) -> Played:
    """The case played with no answer: the truth file of its run, and a silent decoder."""
    return play_case(_ref(case), seed)


@cache
def _random(case: str) -> Played:
    """The random answerer on :data:`SEED`: the receiver's onsets (a stimulus decoder of no
    skill for the classes), random values (``listen --answer --answer-with random``)."""
    if case == "classification":
        return play_case(_ref(case), SEED, listening=lambda end: [
            receiver_with(end, DecisionAnswerer)])
    return play_case(_ref(case), SEED, listening=lambda end: [
        receiver_with(end, lambda r: TaskAnswerer(r, "random", seed=0))])


def _replay(case: str) -> Played:
    """Another seed's truth answered on :data:`SEED`: the oracle of ``listen --answer-with
    oracle --oracle-truth`` fed the truth file of :data:`OTHER_SEED` (for classification, a
    DECISION naming each onset marker's stimulus of that run, 50 ms after it)."""
    truth = _silent(case, OTHER_SEED).truth
    if case == "classification":
        return play_case(_ref(case), SEED, script=g.replay_markers(truth, 0.05))
    path = Path(tempfile.mkdtemp(prefix="skinhil-gamers-")) / "truth.jsonl"
    path.write_text(truth, encoding="utf-8")
    return play_case(_ref(case), SEED, listening=lambda end: [
        receiver_with(end, lambda r: TaskAnswerer(r, "oracle", truth_path=path))])


def _scripted(case: str, values: g.Values, period_s: float, per_beat: int = 1,
              phase_s: float = 0.0, seed: int = SEED) -> Played:
    script = g.cadence(g.task_id(case), values, period_s, _duration_s(case), per_beat)
    shift = tick_of(phase_s)
    return play_case(_ref(case), seed, script={k + shift: v for k, v in script.items()})


def _after_touches(delay_s: float) -> Played:
    """A SLIP ``delay_s`` after each touch-down of the slip case (a decoder that senses
    touches and guesses when the stick ends)."""
    scene = suite_trials(_ref("slip"), SEED).scenario.scene
    assert scene is not None
    slip = g.task_id("slip")
    script = {tick_of(c.start_s + delay_s): [g.command(slip, i + 1, ())]
              for i, c in enumerate(scene.contacts)}
    return play_case(_ref("slip"), SEED, script=script)


SLIP_CADENCES = ((0.1, 0.0), (0.15, 0.05), (0.25, 0.1), (0.5, 0.0), (0.5, 0.25), (1.0, 0.125))
"""Blind SLIP cadences: (period s, phase s), from below the slip window to the response
window and beyond."""
TOUCH_DELAYS_S = (0.125, 0.2)
"""SLIP delays (s) after each touch-down: within the drawn stick (0.05-0.25 s after the
press's ramp)."""


CLASSES = [(float(i),) for i in range(9)]
HZ = (50.0, 100.0, 200.0, 300.0)
GAMERS: dict[str, Any] = {
    "classification-constant": lambda: _scripted("classification", g.constant((4,)),
                                                 CADENCE_S),
    "classification-several-per-onset": lambda: _scripted("classification", g.cycle(CLASSES),
                                                          CADENCE_S, per_beat=9),
    "classification-replay": lambda: _replay("classification"),
    "localisation-constant-centre": lambda: _scripted("localisation", g.constant((0.0, 0.0)),
                                                      CADENCE_S),
    "localisation-spam": lambda: _scripted("localisation", g.uniform((-2.5, -2.5), (2.5, 2.5)),
                                           SPAM_S),
    "localisation-replay": lambda: _replay("localisation"),
    "localisation-silent": lambda: _silent("localisation", OTHER_SEED),
    "force-constant": lambda: _scripted("force", g.constant((0.5,)), CADENCE_S),
    "force-several-per-onset": lambda: _scripted(
        "force", g.cycle([(0.3,), (0.4,), (0.5,), (0.6,), (0.7,)]), CADENCE_S, per_beat=5),
    "slip-every-10ms": lambda: _scripted("slip", g.constant(()), 0.01),
    **{f"slip-cadence-{p:g}s-phase-{ph:g}s": (
        lambda p=p, ph=ph: _scripted("slip", g.constant(()), p, phase_s=ph))
       for p, ph in SLIP_CADENCES},
    **{f"slip-{d:g}s-after-each-touch": (lambda d=d: _after_touches(d))
       for d in TOUCH_DELAYS_S},
    "slip-replay": lambda: _replay("slip"),
    "vibration-several-per-onset": lambda: _scripted("vibration", g.cycle([(f,) for f in HZ]),
                                                     CADENCE_S, per_beat=4),
}
"""Each gamer: its case (the name's first word) played on :data:`SEED` (the silent one on
:data:`OTHER_SEED`, the run whose truth the replays answer)."""

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
    for name in GAMERS])
def test_a_gamer_scores_at_or_below_the_random_answerer(gamer: str) -> None:
    case = gamer.split("-")[0]
    played = GAMERS[gamer]()
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
    played = [_scripted("vibration", g.constant((hz,)), CADENCE_S, seed=s)
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
    played = play_case(_ref("slip"), SEED, listening=lambda end: [
        receiver_with(end, lambda r: TaskAnswerer(r, "reference"))])
    assert played.score("slip") >= 0.8, played.task("slip")


def test_an_answer_repeated_for_a_trial_voids_its_right_answer() -> None:
    """Several answers per onset: the hedges that were right count for nothing, each extra
    answer against the score."""
    s = GAMERS["force-several-per-onset"]().task("force")
    assert s["duplicates"] >= 4 * s["matched"] and s["hedged"] == s["right"]
    assert s["score"] == 0.0


def test_a_silent_decoder_scores_zero_on_every_trial() -> None:
    s = _silent("localisation", OTHER_SEED).task("localisation")
    assert s["answers"] == 0 and s["trials"] > 0 and s["score"] == 0.0
    assert s["misses"] + s["pending"] == s["trials"]


# -- the grip --------------------------------------------------------------------------------

CONSTANT_GRIPS_N = (0.7, 1.5)
"""Constant grips: one that spares the fragile objects, one that holds the sturdy ones."""
MARGIN = 0.25
"""How far (grasp.score) below the reference controller a blind grip must stay."""


@cache
def _grasp_reference() -> Played:
    """The reference grip controller (its load readout fitted on the suite's training
    lifts, as ``listen --grip-readout``'s is fitted) closing the loop on :data:`SEED`."""
    readout: LoadReadout = fit_readout(SNR_DB, runs=readout_training_runs(),
                                       grips_n=SUITE_TRAINING_GRIPS_N)
    return play_case(_ref("grasp"), SEED, listening=lambda end: [
        GripLoop(end, [GripController(end, SlipReflex(readout))])])


def _timetable(duration_s: float) -> g.Script:
    """The documented lift timetable (docs/grasp.md, :class:`GraspParams`' defaults, lifts
    every ``period_s`` from the middle of the lead), gripped without a spike: 1.5 N from
    the hand closing to the object set down, 0.2 N more over the pull's documented time."""
    p = GraspParams()
    targets: list[tuple[float, float]] = []
    start = 0.2
    while start < duration_s:
        rise = start + p.grasp_s
        pull = start + p.pull_start_s()
        targets += [(start, 1.5), (pull, 1.7), (start + p.pull_end_s(), 1.5),
                    (rise + p.rise_s + p.hold_s + p.lower_s, 0.3)]
        start += p.period_s
    return g.grips(sorted(targets), duration_s)


GRIPPERS: dict[str, Any] = {
    "maximum": lambda d: g.held_at(GraspParams().max_grip_n, d),
    **{f"constant-{n:g}N": (lambda d, n=n: g.held_at(n, d)) for n in CONSTANT_GRIPS_N},
    "timetable": _timetable,
    "dither": lambda d: g.dither(0.6, 1.6, 0.1, d),
}

@cache
def _gripped(name: str) -> Played:
    d = suite_trials(_ref("grasp"), SEED).duration_s
    return play_case(_ref("grasp"), SEED, script=GRIPPERS[name](d))


@pytest.mark.parametrize("name", list(GRIPPERS))
def test_a_blind_grip_wins_at_most_one_kind_of_object(name: str) -> None:
    grasp = _gripped(name).scores["grasp"]
    assert grasp["grips"]["accepted"] > 0
    assert sum(v for k, v in grasp["grips"].items() if k.startswith("refused_")) == 0
    assert grasp["score"] <= 0.5, grasp


@pytest.mark.parametrize("name", list(GRIPPERS))
def test_a_blind_grip_scores_well_below_the_reference_controller(name: str) -> None:
    reference = _grasp_reference().score("grasp")
    assert _gripped(name).score("grasp") <= reference - MARGIN


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
    serve = ServeProcess("--suite", _ref(case), "--seed", str(SEED), "--port", pair.path,
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
    script = g.cadence(g.task_id("slip"), g.constant(()), 0.01, _duration_s("slip"))
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
