"""Bad parameters, stimuli and schedule files get a ConfigError naming the problem."""

from pathlib import Path

import pytest

from skinhil import SkinModel, SkinParams, Stimulus, load_schedule
from skinhil.errors import ConfigError


@pytest.mark.parametrize("kwargs, word", [
    ({"mass_kg": -1.0}, "mass_kg"),
    ({"stiffness_n_per_m": 0.0}, "stiffness_n_per_m"),
    ({"damping_n_s_per_m": -0.1}, "damping_n_s_per_m"),
    ({"tension_n": float("nan")}, "tension_n"),
    ({"mechanics": "quantum"}, "mechanics"),
])
def test_bad_skin_params(kwargs: dict, word: str) -> None:
    with pytest.raises(ConfigError, match=word):
        SkinParams(**kwargs)


def test_bad_steps_and_stimuli() -> None:
    model = SkinModel()
    stim = Stimulus("s", {15: (0, 0, -0.1)})
    with pytest.raises(ConfigError, match="dt_s"):
        model.simulate(stim, 0.1, dt_s=0.0)
    with pytest.raises(ConfigError, match="duration_s"):
        model.simulate(stim, -1.0)
    with pytest.raises(ConfigError, match="too large for the geometric"):
        SkinModel(SkinParams(mechanics="geometric")).simulate(stim, 0.1, dt_s=5e-3)
    with pytest.raises(ConfigError, match="unknown mass number 78"):
        Stimulus("s", {78: (0, 0, 1)})
    with pytest.raises(ConfigError, match="fixed mass"):
        model.simulate(Stimulus("s", {1: (0, 0, -0.1)}), 0.01)
    with pytest.raises(ConfigError, match="three"):
        Stimulus("s", {15: (0, 1)})  # type: ignore[dict-item]


def test_schedule_toml(tmp_path: Path) -> None:
    good = tmp_path / "good.toml"
    good.write_text("""
[[stimulus]]
name = "poke"
forces = { 15 = [0.0, 0.0, -0.4], 22 = [0.0, 0.0, -0.1] }
indentation_s = 0.2

[[event]]
start_s = 0.5
stimulus = "poke"

[[event]]
start_s = 0.1
stimulus = "A"
""")
    sched = load_schedule(good)
    assert [e.stimulus.name for e in sched.entries] == ["A", "poke"]
    assert [e.stimulus_id for e in sched.entries] == [10, 100]
    assert sched.duration_s == pytest.approx(0.7)
    f = sched.force_at(__import__("numpy").array([0.55]))
    assert f[0, 14, 2] < 0 and f[0, 21, 2] < 0


@pytest.mark.parametrize("text, word", [
    ("[[event]\nstart_s = 1", "not valid TOML"),
    ("[[event]]\nstart_s = 1\nstimulus = 'nope'", "unknown stimulus 'nope'"),
    ("[[event]]\nstart_s = 'soon'\nstimulus = 'A'", "start_s"),
    ("[[stimulus]]\nname = 'x'\nforces = { 99 = [0, 0, 1] }\n[[event]]\nstart_s = 0\n"
     "stimulus = 'x'", "unknown mass number 99"),
    ("[other]\na = 1", "unknown section"),
    ("", "no \\[\\[event\\]\\]"),
])
def test_malformed_schedule(tmp_path: Path, text: str, word: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=word):
        load_schedule(path)
    with pytest.raises(ConfigError, match="not found"):
        load_schedule(tmp_path / "missing.toml")
