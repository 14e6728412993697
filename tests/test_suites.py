"""The task suite ``tactile-v1`` (skinhil.suites, docs/suites.md): its trials come from the
seed, its generators are frozen (digests pinned), its rules hold for every draw, a case ends
by itself under ``serve --suite``, and ``skinhil suites`` lists it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from harness.peers import UdpPeer
from harness.serve import run_serve

import protocols
from skinhil.cli import main
from skinhil.errors import ConfigError
from skinhil.model.skin import SkinParams
from skinhil.plant import GraspParams, HeldObject
from skinhil.plant.lifts import G_M_PER_S2, Lift, LiftScene, drawn_lift_scene
from skinhil.plant.report import plant_scores
from skinhil.schemas import validate
from skinhil.suites import SUITES, case_ref, suite_trials
from skinhil.suites.draws import inner_half_extent_m
from skinhil.suites.tactile_v1 import (
    EVALUATION_SEEDS,
    FRAGILE_MASS_KG,
    STURDY_MASS_KG,
    TRAINING_SEEDS,
)
from skinhil.tasks import by_name, tasks_mask

SUITE = SUITES["tactile-v1"]
CASES = [c.name for c in SUITE.cases]

DIGESTS = {
    # frozen: a change here is a new suite version (tactile-v2), never an edit
    "classification": [
        "0d17e3accd8b4efbb3cc07e2816a83731e961bfd8642b1d711cac2acc2cfc1c9",
        "aeaa6fa0b5c8d7a06d57e2a324bd75776e321e428031314cc5125374de9265ec",
        "45bfcf753ddd81bff9110cd4d0a5c2d3c12e93d24ea1f98dd95e8b813a169d15",
    ],
    "localisation": [
        "84655d622011b108dd2e8c0b041fcc584faa3e5db94476d5fc10c734d31c0ccf",
        "f3ce3d39e2fe20bfd53f2a89c1b537e2ac65b7f058f1396c6bac1fd1f4a853a8",
        "899b965a6caf397e921ce2466f6175eed0e93b7979b092ad3c17df1b0eb9a940",
    ],
    "force": [
        "583fc9bb0792d26440b627ce1197f923c62a513be71ece7160c70ede2f34681d",
        "1dc7f5b318e376c5dca92ee3be58b4f5e75e9df298990c3dda5650eef56a1999",
        "421fb2387a954c2978d05185b96a0f03aef808aa1b60ef7da26dbc388fb09ede",
    ],
    "slip": [
        "4fd60b2ed66fa13855e460d17242b45e33d2d2b95faaf95bac19616f899be7a2",
        "2c3e9f64f32f266e28c554ae1f8d794b5131f877d8ba136c9ffcae5636b6aab9",
        "09e9ef9c7b4ab3c464885acdb1edb961ccc5bee797726496bf049a2ce712f8d9",
    ],
    "vibration": [
        "256a0e6791aeaa50d0ba03963fecb42c99743e5038748894dd2feea4fe48c3d8",
        "f8c1180e9107a4ae925d280dca1d3799fae09e38f3d488f25a659479f2f8dfaa",
        "eb69e1a1b336be3a63a3666e768e5512be4d5feeb8185b9cf8aceb4826bc9dc7",
    ],
    "grasp": [
        "2e7e83a5531227067611b0cfb1176ef975334147a3c8931e01a6b1c892bc1013",
        "059e27e19df89009f16ef1c7ab4efe06e160168832c764efa89efb388806e697",
        "b8488ffaef62920383612d022152eb0b6e4bee16e53c9be77bd442480640f2a2",
    ],
}
"""sha256 of the trials of seeds 1, 2 and 1,000,000 per case."""
SEEDS = (1, 2, 1_000_000)


def test_the_suite_has_its_six_cases() -> None:
    assert CASES == ["classification", "localisation", "force", "slip", "vibration", "grasp"]


@pytest.mark.parametrize("case", CASES)
def test_the_trials_of_a_version_are_frozen(case: str) -> None:
    got = [suite_trials(f"tactile-v1:{case}", seed).digest() for seed in SEEDS]
    assert got == DIGESTS[case]


@pytest.mark.parametrize("case", CASES)
def test_two_seeds_give_different_trials(case: str) -> None:
    a, b = (suite_trials(f"tactile-v1:{case}", seed) for seed in (5, 6))
    assert a.digest() != b.digest()
    assert a.description()["contacts"] != b.description()["contacts"] or (
        a.description()["stimuli"] != b.description()["stimuli"])
    assert suite_trials(f"tactile-v1:{case}", 5).digest() == a.digest()


def test_training_and_evaluation_seeds_are_disjoint() -> None:
    assert set(range(TRAINING_SEEDS.stop - 5, TRAINING_SEEDS.stop)).isdisjoint(
        range(EVALUATION_SEEDS.start, EVALUATION_SEEDS.start + 5))
    assert TRAINING_SEEDS.stop <= EVALUATION_SEEDS.start
    with pytest.raises(ConfigError, match="overlap"):
        type(SUITE)("x", 1, "", SUITE.cases, range(0, 10), range(5, 20))


def test_a_case_poses_only_the_tasks_whose_value_varies() -> None:
    posed = {c.name: [t.name for t in c.tasks] for c in SUITE.cases}
    assert posed == {"classification": ["classification"], "localisation": ["localisation"],
                     "force": ["force"], "slip": ["slip"], "vibration": ["vibration"],
                     "grasp": []}
    assert SUITE.case("grasp").held_object
    force = suite_trials("tactile-v1:force", 3).scenario.scene
    assert force is not None
    places = {tuple(c.trajectory.keyframes[:, 1:3].ravel()) for c in force.contacts}
    assert len(places) == 1  # the force case's place is fixed: no localisation posed
    loads = {float(c.trajectory.keyframes[:, 3].max()) for c in force.contacts}
    assert len(loads) == len(force.contacts)
    vib = SUITE.case("vibration").tasks[0]
    assert vib.classes == (50.0, 100.0, 200.0, 300.0)


@pytest.mark.parametrize("size", [(6, 6), (8, 10)])
def test_places_cover_the_inner_area_the_skin_size_decides(size: tuple[int, int]) -> None:
    hx, hy = inner_half_extent_m(size, SkinParams.spacing_m)
    xy = np.concatenate([
        np.array([c.trajectory.keyframes[0, 1:3] for c in t.scenario.scene.contacts])
        for t in (SUITE.case("localisation").generate(SUITE.id, s, size) for s in range(20))])
    assert np.all(np.abs(xy[:, 0]) <= hx) and np.all(np.abs(xy[:, 1]) <= hy)
    assert np.abs(xy[:, 0]).max() > 0.8 * hx and np.abs(xy[:, 1]).max() > 0.8 * hy


def test_onsets_are_jittered_not_periodic() -> None:
    scene = suite_trials("tactile-v1:localisation", 9).scenario.scene
    assert scene is not None
    intervals = np.diff([c.start_s for c in scene.contacts])
    assert intervals.min() > 0 and intervals.max() - intervals.min() > 0.05


@pytest.mark.parametrize("seed", range(30))
def test_no_constant_grip_both_holds_and_spares_every_object(seed: int) -> None:
    trials = suite_trials("tactile-v1:grasp", seed)
    params, scene = trials.grasp, trials.scenario.scene
    assert isinstance(scene, LiftScene) and params is not None
    need = np.array([lift.mass_kg * G_M_PER_S2 / params.mu_static for lift in scene.lifts])
    brk = np.array([lift.break_n for lift in scene.lifts])
    most = np.array([(lift.mass_kg * G_M_PER_S2 + lift.pull_n) / params.mu_static
                     for lift in scene.lifts])
    assert np.all(brk < params.max_grip_n) and np.all(most < brk)  # each lift can be won
    assert need.max() > brk.min()  # a grip that holds the heaviest breaks the most fragile
    fragile = [lift.mass_kg <= FRAGILE_MASS_KG[1] for lift in scene.lifts]
    assert any(fragile) and not all(fragile)
    assert all(STURDY_MASS_KG[0] <= lift.mass_kg for lift, f in zip(scene.lifts, fragile,
                                                                     strict=True) if not f)
    pulls = [params.pull_start_s(lift) for lift in scene.lifts]
    assert len(set(pulls)) == len(pulls)  # the perturbation's time is drawn per lift


def _lift_run(grip_n: float, break_n: float) -> dict[str, object]:
    """One light lift held at a constant grip off the clock: the score file's grasp."""
    from skinhil.model.sensor import SkinSensor
    from skinhil.model.skin import SkinModel
    from skinhil.model.stimuli import Schedule
    from skinhil.world import TouchSensor, TruthLog

    params = GraspParams()
    scene = drawn_lift_scene(params, [Lift(0.05, 0.03, break_n, 0.15, 0.1, 0.1)])
    sensor = SkinSensor(SkinModel(SkinParams()), 1e-4, float("inf"), 1, state_forces=True)
    touch = TouchSensor(sensor, scene)
    plant = HeldObject(params, touch.world, 1000)
    plant.grip_n = grip_n
    truth = TruthLog()
    touch.start(0.0)
    for k in range(int(round((0.05 + params.lift_duration_s(scene.lifts[0])) / 1e-3)) + 5):
        plant.before_tick()
        _, _, raw = touch.advance_schedule(Schedule(()), 10)
        truth.add_object(plant.after_tick(k * 1000, k * 1e-3, 1e-4, raw))
    return plant_scores(plant, truth)


def test_a_grip_above_the_break_force_breaks_the_object_and_fails_the_lift() -> None:
    spared = _lift_run(0.8, break_n=0.9)
    assert spared["held"] == 1 and spared["broken"] == 0 and spared["score"] == 1.0
    broken = _lift_run(1.0, break_n=0.9)
    assert broken["held"] == 1 and broken["broken"] == 1 and broken["score"] == 0.0
    assert broken["broken_lifts"] == [1]
    for scores in (spared, broken):  # the score file's "grasp", against its schema
        validate("score#/$defs/grasp", scores)


def test_a_bad_suite_reference_says_what_to_give() -> None:
    with pytest.raises(ConfigError, match="SUITE:CASE"):
        case_ref("tactile-v1")
    with pytest.raises(ConfigError, match="tactile-v1"):
        case_ref("tactile-v9:force")
    with pytest.raises(ConfigError, match="classification, localisation"):
        case_ref("tactile-v1:juggling")


def test_skinhil_suites_lists_suites_cases_versions_and_tasks(capsys) -> None:
    assert main(["suites", "--json"]) == 0
    (s,) = json.loads(capsys.readouterr().out)["suites"]
    assert s["suite"] == "tactile-v1" and s["version"] == 1
    assert [c["case"] for c in s["cases"]] == CASES
    assert s["evaluation_seeds"][0] > s["training_seeds"][1]
    assert main(["suites"]) == 0
    text = capsys.readouterr().out
    assert "tactile-v1:grasp" in text and "localisation (±0.5 mm)" in text


@pytest.mark.parametrize("case", CASES)
def test_serve_suite_case_ends_by_itself(case: str) -> None:
    peer = UdpPeer()
    try:
        trials = suite_trials(f"tactile-v1:{case}", 11)
        done = run_serve("--suite", f"tactile-v1:{case}", "--seed", "11", "--udp",
                         f"127.0.0.1:{peer.port}", "--json", timeout_s=300)
        assert done.returncode == 0, done.stderr
        assert peer.wait_for(lambda p: len(p.of(protocols.RunEnd)) > 0, 10)
        sessions = peer.of(protocols.Session)
    finally:
        peer.close()
    summary = next(json.loads(line) for line in done.stdout.splitlines()
                   if json.loads(line).get("type") == "summary")
    assert summary["ticks"] == int(round(trials.duration_s / 1e-3))
    if case == "grasp":
        assert summary["grasp"]["lifts"] == len(trials.scenario.scene.contacts)
    # the SESSION announces exactly the tasks the case poses (classification always)
    posed = {"classification", *(t.name for t in trials.tasks)}
    assert sessions and sessions[0].tasks == tasks_mask(by_name(n).wire_id for n in posed)
    assert set(summary["tasks"]) == posed - {"classification"}


def test_a_case_plays_fewer_trials_when_asked_never_more() -> None:
    case = SUITE.case("localisation")
    short = case.generate(SUITE.id, 4, trials=2)
    assert short.scenario.scene is not None and len(short.scenario.scene.contacts) == 2
    assert short.duration_s == short.scenario.duration_s + case.tail_s
    assert short.duration_s < case.generate(SUITE.id, 4).duration_s
    with pytest.raises(ConfigError, match="1..8 trials"):
        case.generate(SUITE.id, 4, trials=9)
