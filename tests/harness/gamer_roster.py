"""The roster of scripted decoders that read no spike (issue 41), each a function of the
evaluation seed it is scored on (and of the other seed whose truth the replaying gamers
answer), beside the baselines they are held to: the random answerer and the reference grip
controller, played the same way on the same seed.

Every one is played off the clock (:func:`harness.suite_play.play_case`: every command at
its tick) and scored by the board through its wire commands; ``tests/test_suite_gamers.py``
asserts on one seed, ``benchmarks/bench_gamers.py`` pools them over seeds drawn at run time.
A gamer's name starts with its case (:func:`case_of`).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from functools import cache
from pathlib import Path

from harness import gamers as g
from harness.suite_play import SNR_DB, Played, play_case, receiver_with, tick_of
from skinhil.cli.demo_grasp import readout_training_runs
from skinhil.plant import GraspParams
from skinhil.receiver.answer import DecisionAnswerer
from skinhil.receiver.grip_loop import GripLoop
from skinhil.receiver.grip_reflex import GripController, LoadReadout, SlipReflex
from skinhil.receiver.grip_training import SUITE_TRAINING_GRIPS_N, fit_readout
from skinhil.receiver.task_answer import TaskAnswerer
from skinhil.suites import suite_trials

SUITE = "tactile-v1"
CADENCE_S = 0.5
"""The constant answerers' period (s): the response window, about one answer per trial."""
SPAM_S = 0.005
"""The spammers' period (s)."""
SLIP_CADENCES = ((0.1, 0.0), (0.15, 0.05), (0.25, 0.1), (0.5, 0.0), (0.5, 0.25), (1.0, 0.125))
"""Blind SLIP cadences: (period s, phase s), from below the slip window to the response
window and beyond."""
TOUCH_DELAYS_S = (0.125, 0.2)
"""SLIP delays (s) after each touch-down: within the drawn stick (0.05-0.25 s after the
press's ramp)."""
CLASSES = [(float(i),) for i in range(9)]
"""The classification classes (the paper's 9 direction conditions' stimulus ids)."""
HZ = (50.0, 100.0, 200.0, 300.0)
"""The vibration classes (Hz)."""
CONSTANT_HZ = (50.0, 300.0)
"""The constant vibration classes (Hz) played at the response window's cadence."""
CONSTANT_GRIPS_N = (0.7, 1.5)
"""Constant grips (N): one that spares the fragile objects, one that holds the sturdy ones."""
GRASP_MARGIN = 0.25
"""How far (``grasp.score``) below the reference controller a blind grip must stay."""

Gamer = Callable[[int, int], Played]
"""A gamer: (evaluation seed, other seed whose truth a replay answers) -> the played case."""
Gripper = Callable[[int], Played]
"""A blind grip: evaluation seed -> the played grasp case."""


def ref(case: str) -> str:
    """``SUITE:CASE``."""
    return f"{SUITE}:{case}"


def case_of(name: str) -> str:
    """The case a gamer plays: its name's first word."""
    return name.split("-")[0]


def duration_s(case: str, seed: int) -> float:
    """How long ``case`` of ``seed`` runs (s)."""
    return suite_trials(ref(case), seed).duration_s


@cache
def silent(case: str, seed: int) -> Played:
    """The case played with no answer: the truth file of its run, and a silent decoder."""
    return play_case(ref(case), seed)


@cache
def random_answerer(case: str, seed: int) -> Played:
    """The random answerer on ``seed``: the receiver's onsets (a stimulus decoder of no
    skill for the classes), random values (``listen --answer --answer-with random``)."""
    if case == "classification":
        return play_case(ref(case), seed, listening=lambda end: [
            receiver_with(end, DecisionAnswerer)])
    return play_case(ref(case), seed, listening=lambda end: [
        receiver_with(end, lambda r: TaskAnswerer(r, "random", seed=0))])


def reference_answerer(case: str, seed: int) -> Played:
    """The reference answerer (``listen --answer --answer-with reference``) on ``seed``."""
    return play_case(ref(case), seed, listening=lambda end: [
        receiver_with(end, lambda r: TaskAnswerer(r, "reference"))])


def replay(case: str, seed: int, other_seed: int) -> Played:
    """``other_seed``'s truth answered on ``seed``: the oracle of ``listen --answer-with
    oracle --oracle-truth`` fed the truth file of ``other_seed`` (for classification, a
    DECISION naming each onset marker's stimulus of that run, 50 ms after it)."""
    truth = silent(case, other_seed).truth
    if case == "classification":
        return play_case(ref(case), seed, script=g.replay_markers(truth, 0.05))
    with tempfile.TemporaryDirectory(prefix="skinhil-gamers-") as tmp:
        path = Path(tmp) / "truth.jsonl"
        path.write_text(truth, encoding="utf-8")
        return play_case(ref(case), seed, listening=lambda end: [
            receiver_with(end, lambda r: TaskAnswerer(r, "oracle", truth_path=path))])


def scripted(case: str, values: g.Values, period_s: float, seed: int, per_beat: int = 1,
             phase_s: float = 0.0) -> Played:
    """``per_beat`` answers of ``values`` every ``period_s`` (s) from ``phase_s`` (s) on,
    over ``case`` of ``seed``."""
    script = g.cadence(g.task_id(case), values, period_s, duration_s(case, seed), per_beat)
    shift = tick_of(phase_s)
    return play_case(ref(case), seed, script={k + shift: v for k, v in script.items()})


def after_touches(delay_s: float, seed: int) -> Played:
    """A SLIP ``delay_s`` (s) after each touch-down of the slip case of ``seed`` (a decoder
    that senses touches and guesses when the stick ends)."""
    scene = suite_trials(ref("slip"), seed).scenario.scene
    if scene is None:
        raise ValueError(f"{ref('slip')} of seed {seed} has no scene to touch")
    slip = g.task_id("slip")
    script = {tick_of(c.start_s + delay_s): [g.command(slip, i + 1, ())]
              for i, c in enumerate(scene.contacts)}
    return play_case(ref("slip"), seed, script=script)


GAMERS: dict[str, Gamer] = {
    "classification-constant": lambda s, o: scripted("classification", g.constant((4,)),
                                                     CADENCE_S, s),
    "classification-several-per-onset": lambda s, o: scripted(
        "classification", g.cycle(CLASSES), CADENCE_S, s, per_beat=9),
    "classification-replay": lambda s, o: replay("classification", s, o),
    "localisation-constant-centre": lambda s, o: scripted(
        "localisation", g.constant((0.0, 0.0)), CADENCE_S, s),
    "localisation-spam": lambda s, o: scripted(
        "localisation", g.uniform((-2.5, -2.5), (2.5, 2.5)), SPAM_S, s),
    "localisation-replay": lambda s, o: replay("localisation", s, o),
    "localisation-silent": lambda s, o: silent("localisation", s),
    "force-constant": lambda s, o: scripted("force", g.constant((0.5,)), CADENCE_S, s),
    "force-several-per-onset": lambda s, o: scripted(
        "force", g.cycle([(0.3,), (0.4,), (0.5,), (0.6,), (0.7,)]), CADENCE_S, s, per_beat=5),
    "slip-every-10ms": lambda s, o: scripted("slip", g.constant(()), 0.01, s),
    **{f"slip-cadence-{p:g}s-phase-{ph:g}s": (
        lambda s, o, p=p, ph=ph: scripted("slip", g.constant(()), p, s, phase_s=ph))
       for p, ph in SLIP_CADENCES},
    **{f"slip-{d:g}s-after-each-touch": (lambda s, o, d=d: after_touches(d, s))
       for d in TOUCH_DELAYS_S},
    "slip-replay": lambda s, o: replay("slip", s, o),
    "vibration-several-per-onset": lambda s, o: scripted(
        "vibration", g.cycle([(f,) for f in HZ]), CADENCE_S, s, per_beat=4),
}
"""Each gamer, played on the evaluation seed; the replays answer the other seed's truth."""

CONSTANT_CLASSES: dict[str, Gamer] = {
    f"vibration-constant-{hz:g}Hz": (
        lambda s, o, hz=hz: scripted("vibration", g.constant((hz,)), CADENCE_S, s))
    for hz in CONSTANT_HZ}
"""A constant vibration class at the response window's cadence: it meets a random class
only in expectation (chance = 1 / classes), so it is compared over seeds, not on one."""


@cache
def grasp_reference(seed: int) -> Played:
    """The reference grip controller (its load readout fitted on the suite's training
    lifts, as ``listen --grip-readout``'s is fitted) closing the loop on ``seed``."""
    readout: LoadReadout = fit_readout(SNR_DB, runs=readout_training_runs(),
                                       grips_n=SUITE_TRAINING_GRIPS_N)
    return play_case(ref("grasp"), seed, listening=lambda end: [
        GripLoop(end, [GripController(end, SlipReflex(readout))])])


def timetable(duration_s: float) -> g.Script:
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


GRIP_SCRIPTS: dict[str, Callable[[float], g.Script]] = {
    "maximum": lambda d: g.held_at(GraspParams().max_grip_n, d),
    **{f"constant-{n:g}N": (lambda d, n=n: g.held_at(n, d)) for n in CONSTANT_GRIPS_N},
    "timetable": timetable,
    "dither": lambda d: g.dither(0.6, 1.6, 0.1, d),
}
"""Each blind grip's GRIPs over a grasp case of the given length (s)."""


@cache
def gripped(name: str, seed: int) -> Played:
    """The grasp case of ``seed`` gripped by :data:`GRIP_SCRIPTS` ``[name]``."""
    return play_case(ref("grasp"), seed,
                     script=GRIP_SCRIPTS[name](duration_s("grasp", seed)))


GRIPPERS: dict[str, Gripper] = {
    name: (lambda s, name=name: gripped(name, s)) for name in GRIP_SCRIPTS}
"""Each blind grip, played on the evaluation seed."""
