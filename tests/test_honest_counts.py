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


def test_the_boards_grip_counts_are_the_hosts_acks() -> None:
    """A burst of GRIPs beyond the command queue, off the clock: every GRIP the board
    received is counted once in its score (accepted, refused by the object or BUSY), the
    accepted ones are the ACKs on the wire, and the NACKs on the wire are refusals."""
    from harness.golden import GoldenLink

    import protocols
    from firmware_sim.board import Board, BoardConfig
    from firmware_sim.score import grasp_scores
    from skinhil.model.timeline import Timeline
    from skinhil.plant import lift_scene

    burst = 100
    link = GoldenLink(frames=False)
    enc, dec = link.codec_pair()
    link.script = {5: [enc.command(protocols.Command(t, protocols.CommandCode.GRIP, 1.0))
                       for t in range(1, burst + 1)]}
    params = GraspParams()
    board = Board(BoardConfig(seed=7, schedule_mode=Timeline.SCHEDULE_FILE), lambda: link,
                  scene=lift_scene(params, 1), grasp=params)
    board.warm_up()
    board.queue_session(protocols.SessionReason.START)
    for k in range(300):
        link.tick = k
        board.tick()
    board.finish()
    grips = grasp_scores(board)["grasp"]["grips"]
    acks = [r for r in dec.feed(b"".join(link.units)).records
            if isinstance(r, protocols.Ack) and r.opcode == protocols.CommandCode.GRIP]
    refused = sum(v for k, v in grips.items() if k.startswith("refused_"))
    assert grips["refused_busy"] > 0  # the burst overflowed the queue
    assert grips["accepted"] + refused == burst
    assert grips["accepted"] == sum(a.ok for a in acks)
    nacks = [a for a in acks if not a.ok]
    assert 0 < len(nacks) <= refused
    assert {a.reason for a in nacks} <= {protocols.NackReason.BUSY,
                                         protocols.NackReason.GRIP_LIMIT}


def test_the_grasp_demo_stopped_with_ctrl_c_prints_the_lifts_played() -> None:
    """``demo --task grasp`` stopped: the board (in a session of its own) gets one SIGINT,
    ends cleanly and scores the lifts it played; the demo prints them and exits 130."""
    import re

    lifts = 20
    demo = ServeProcess("--task", "grasp", "--lifts", str(lifts), "--controller", "off",
                        command="demo")
    try:
        end = time.monotonic() + 300
        while not any(x.get("text", "").startswith("board:") for x in list(demo.lines)):
            assert time.monotonic() < end and not demo.exited, demo.stderr
            time.sleep(0.05)
        time.sleep(8.0)  # the board starts (kernels warm: the tests above ran serve) and lifts
        assert not demo.exited, demo.stderr
        demo.interrupt()
        status = demo.wait(120)
    finally:
        demo.kill()
    text = "".join(x.get("text", "") for x in demo.lines)
    assert status == 130, demo.stderr
    found = re.search(r"grasp: score \S+; (\d+)/(\d+) lifts held", text)
    assert found is not None, text + demo.stderr
    assert 1 <= int(found.group(2)) < lifts
