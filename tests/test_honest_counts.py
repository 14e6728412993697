"""Honest, announced results: ``serve --grasp N`` ends after its N lifts, a grasp run stopped
with Ctrl-C scores the lifts it played, every file serve writes is announced with its path."""

from __future__ import annotations

import json
import time
from pathlib import Path

from harness.serve import ServeProcess, run_serve

from skinhil.plant import GraspParams, lifts_duration_s
from skinhil.process_output import SUMMARY, last_record


def test_grasp_run_ends_after_its_lifts_and_says_where_it_wrote(tmp_path: Path) -> None:
    score, truth, held = tmp_path / "score.json", tmp_path / "truth.jsonl", tmp_path / "held.bin"
    run = run_serve("--link", "pty:", "--grasp", "1", "--score", str(score), "--truth",
                    str(truth), "--grasp-truth", str(held), "--json", timeout_s=300)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = last_record([json.loads(x) for x in run.stdout.splitlines()], SUMMARY)
    assert summary is not None, run.stdout
    assert summary["board_time_s"] == lifts_duration_s(GraspParams(), 1)
    assert json.loads(score.read_text())["grasp"]["lifts"] == 1
    for what, path in (("the score", score), ("the ground truth", truth),
                       ("the held object's truth", held)):
        assert f"skinhil serve: wrote {what} to {path.resolve()}\n" in run.stderr
        assert path.is_file()
    assert held.stat().st_size > 0  # a record a tick (the ground truth of lifts: no trial)


def test_a_grasp_run_stopped_with_ctrl_c_scores_the_lifts_it_played(tmp_path: Path) -> None:
    params = GraspParams()
    score = tmp_path / "score.json"
    board = ServeProcess("--link", "pty:", "--grasp", "3", "--score", str(score), "--json")
    try:
        board.wait_ready()
        end = time.monotonic() + 120
        while not any(x.get("type") == "status" and x["board_time_s"] > 1.3 * params.period_s
                      for x in list(board.lines)):
            assert time.monotonic() < end and not board.exited, board.stderr
            time.sleep(0.05)
        board.interrupt()
        board.wait(60)
    finally:
        board.kill()
    played_s = board.summary()["board_time_s"]
    assert played_s < lifts_duration_s(params, 3)  # stopped before the end
    started = int(played_s // params.period_s) + 1
    assert json.loads(score.read_text())["grasp"]["lifts"] == started >= 2
    assert f"wrote the score to {score.resolve()}" in board.stderr
