"""Tasks are a registry: the built-in ones are the ``skinhil.tasks`` entry points, and a task
declared by a package of its own (a module and an entry point, nothing else) is on the wire,
in the DBC and on the board's scoreboard."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np
import pytest
from harness.host_link import host_beside_serve

import protocols
from skinhil.errors import ConfigError
from skinhil.scoring import TaskScoreboard
from skinhil.tasks import TaskDef, TrialKind, registry
from skinhil.world.truth import RAW_FIELDS, T_NODES, T_NORMAL

BUILT_IN = ("classification", "localisation", "force", "slip", "vibration")
ROOT = Path(__file__).resolve().parents[1]

NEW_TASK = '''
import protocols
from skinhil.tasks import TaskDef, TrialKind, Verdict

def rule(trial, values, judging):
    return Verdict(values[0] >= 0.5 * trial.normal_n, abs(values[0] - trial.normal_n))

TASK = TaskDef(layout=protocols.AnswerLayout(7, "pressure", ("pressure_kpa",), scale=1e-3,
                                             units=("kPa",)),
               trials=TrialKind.TOUCH, truth=("normal_n",), rule=rule, error_unit="kpa",
               oracle_values=lambda truth: (float(truth["normal_n"]),))
'''
"""A task no file of the project names: id 7, one value in kPa, posed at every touch."""

PROBE = '''
import json
import numpy as np
import protocols
from protocols.dbc import dbc_text
from skinhil.scoring import TaskScoreboard
from skinhil.tasks import registry
from skinhil.world.truth import RAW_FIELDS, T_NODES, T_NORMAL

board = TaskScoreboard([0.0], response_window_s=0.3)
row = np.zeros((1, RAW_FIELDS)); row[0, T_NODES] = 3; row[0, T_NORMAL] = 0.4
board.observe(1000, row)
enc, dec = protocols.SerialEncoder(), protocols.SerialDecoder()
answer = dec.feed(enc.command(protocols.Answer(1, 7, (0.3,)))).records[0]
outcome = board.answer(answer, 2000)
print(json.dumps({"tasks": [t.name for t in registry.tasks().values()],
                  "values": list(answer.values), "outcome": outcome,
                  "in_dbc": "AnswerPressureKpa" in dbc_text(0),
                  "summary": board.summary()["pressure"]}))
'''


def test_the_built_in_tasks_are_the_skinhil_tasks_entry_points() -> None:
    eps = {ep.name: ep for ep in entry_points(group=registry.GROUP)}
    assert set(BUILT_IN) <= set(eps)
    for name in BUILT_IN:
        task = eps[name].load()
        assert isinstance(task, TaskDef)
        assert eps[name].value == f"skinhil.tasks.{name}:TASK"
        assert task.name == name and task.wire_id == protocols.Task[name.upper()]
        assert registry.task(task.wire_id) is task
        assert task.layout == protocols.ANSWER_LAYOUTS[task.wire_id]


def test_the_scoreboard_poses_the_tasks_by_their_trials() -> None:
    still = TaskScoreboard([0.0], 0.3)
    assert [still.tasks[t].task.name for t in still.tasks] == ["localisation", "force", "slip"]
    shaking = TaskScoreboard([100.0], 0.3)
    assert "vibration" in [s.task.name for s in shaking.tasks.values()]
    assert registry.by_name("classification").trials is TrialKind.NONE


def test_a_clashing_task_is_refused_in_one_line() -> None:
    clash = TaskDef(layout=protocols.AnswerLayout(1, "elsewhere", ("x_mm",)),
                    trials=TrialKind.TOUCH)
    with pytest.raises(ConfigError, match="clashes with 'localisation'"):
        registry.register(clash)
    with pytest.raises(ConfigError, match="no task 'nothing'"):
        registry.by_name("nothing")


def test_a_touch_trial_is_judged_by_its_task_rule() -> None:
    board = TaskScoreboard([0.0], 0.3)
    row = np.zeros((1, RAW_FIELDS))
    row[0, T_NODES], row[0, T_NORMAL] = 3, 0.4
    board.observe(1000, row)
    force = protocols.Answer(1, protocols.Task.FORCE, (0.43,))
    assert board.answer(force, 2000) == "right"
    assert board.summary()["force"]["median_error_n"] == pytest.approx(0.03)


def test_a_task_from_its_own_package_is_registered_encoded_and_scored(tmp_path: Path) -> None:
    _write_package(tmp_path)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    out = subprocess.run([sys.executable, "-c", PROBE], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True, timeout=300)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["tasks"] == [*BUILT_IN, "pressure"]
    assert got["values"] == pytest.approx([0.3])
    assert got["outcome"] == "right"
    assert got["in_dbc"]
    assert got["summary"]["trials"] == 1 and got["summary"]["right"] == 1
    assert got["summary"]["median_error_kpa"] == pytest.approx(0.1)


SCENARIO = """
[[indenter]]
name = "ball"
shape = "sphere"
radius_mm = 5.0

[[contact]]
indenter = "ball"
start_s = 1.5
motion = "press"
load_n = 0.3
ramp_s = 0.03
hold_s = 0.4
"""
"""One press, late enough that the scripted host is answering by then: one touch trial of
every touch task."""

HOST = '''
import os, select, sys, time
import protocols
import skinhil.tasks
skinhil.tasks.tasks()  # the installed tasks' answer layouts, this one's among them
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)
enc, token = protocols.SerialEncoder(), 0
next_s = None
while True:
    if select.select([fd], [], [], 0.02)[0] and os.read(fd, 65536) and next_s is None:
        next_s = time.monotonic()  # the board is up: answer from now on
    if next_s is not None and time.monotonic() >= next_s:
        token += 1
        os.write(fd, enc.command(protocols.Answer(token, 7, (0.3,))))
        next_s += 0.1
'''
"""A scripted decoder under test: from the board's first bytes on, a pressure ANSWER every
0.1 s, whatever it hears."""


def test_a_task_from_its_own_package_is_posed_answered_over_a_pty_and_scored(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _write_package(tmp_path)
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    (tmp_path / "press.toml").write_text(SCENARIO, encoding="utf-8")
    (tmp_path / "host.py").write_text(HOST, encoding="utf-8")
    score = tmp_path / "score.json"
    board, host = host_beside_serve(
        tmp_path, [sys.executable, str(tmp_path / "host.py"), "{HOST}"],
        ["--schedule", str(tmp_path / "press.toml"), "--duration", "2.5", "--snr-db", "inf",
         "--response-window", "0.3", "--score", str(score)], timeout_s=240)
    assert board.returncode == 0, board.stderr
    pressure = json.loads(score.read_text(encoding="utf-8"))["tasks"]["pressure"]
    assert pressure["trials"] == 1
    assert pressure["answers"] > 1, host.stderr[-2000:]
    assert pressure["right"] == 1 and pressure["matched"] == 1, [
        (v["t_us"], v["outcome"], v["trial_t_us"], v["error"]) for v in pressure["verdicts"]]


def _write_package(folder: Path) -> None:
    """The pressure task as a package of its own: its module and its entry point."""
    (folder / "pressure_task.py").write_text(textwrap.dedent(NEW_TASK), encoding="utf-8")
    info = folder / "pressure_task-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: pressure-task\nVersion: 1.0\n",
                                   encoding="utf-8")
    (info / "entry_points.txt").write_text("[skinhil.tasks]\npressure = pressure_task:TASK\n",
                                           encoding="utf-8")
