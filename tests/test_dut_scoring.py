"""The board scores a decoder under test: its DECISIONs against the ground truth.

The matching rule and the scoreboard alone first (every outcome, memory bounded), then a
scripted decoder on a real pty against ``skinhil serve``: right, wrong, twice, late, a false
alarm, an unknown id, while stopped and not at all each land in their own counter.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from harness.peers import PtyPeer
from harness.schemas import check_file, check_lines, check_process_lines
from harness.serve import ServeProcess, run_serve

import protocols
from skinhil.errors import ConfigError
from skinhil.scoring import (
    DecisionScoreboard,
    MatchKind,
    OnsetMatcher,
    Outcome,
    scoreboard_text,
)

MS = 1000


def test_matcher_rule_every_kind() -> None:
    m = OnsetMatcher(window_us=100 * MS)
    assert m.match(5 * MS).kind is MatchKind.NO_STIMULUS  # before any onset
    m.add_onset(10 * MS, 3)
    got = m.match(60 * MS)
    assert got.kind is MatchKind.MATCHED and got.onset is not None and got.onset.t_us == 10 * MS
    assert m.match(110 * MS).kind is MatchKind.DUPLICATE  # the window includes its end
    assert m.match(111 * MS).kind is MatchKind.NO_STIMULUS  # after a decided onset's window
    m.add_onset(200 * MS, 4)
    assert m.match(199 * MS).kind is MatchKind.NO_STIMULUS  # the latest onset *before* it
    assert m.resolve(300 * MS) == 0 and m.pending == 1  # t0 + window not passed yet
    assert m.resolve(300 * MS + 1) == 1 and m.misses == 1
    assert m.match(350 * MS).kind is MatchKind.LATE  # the missed onset's late answer
    m.add_onset(400 * MS, 5)
    assert m.match(400 * MS).kind is MatchKind.MATCHED  # at the onset itself


def test_matcher_forgets_resolved_onsets() -> None:
    m = OnsetMatcher(window_us=10 * MS)
    for i in range(100_000):
        m.add_onset(i * 20 * MS, i % 9)
        if i % 2:
            assert m.match(i * 20 * MS + 5 * MS).kind is MatchKind.MATCHED
        m.resolve(i * 20 * MS + 15 * MS)
    assert len(m._open) == 1 and m.onsets == 100_000 and m.misses == 50_000


def test_scoreboard_counts_every_decision_once() -> None:
    known = {0, 1, 2, 3}
    sb = DecisionScoreboard(0.1, lambda sid: sid in known)
    sb.onset(1, 0)
    outcomes = [sb.decision(1, 40 * MS, 0.9), sb.decision(2, 50 * MS),
                sb.decision(7, 60 * MS), sb.decision(1, 70 * MS, running=False)]
    sb.onset(2, 500 * MS)
    sb.onset(3, 1000 * MS)
    sb.advance(1200 * MS)
    outcomes += [sb.decision(3, 1200 * MS), sb.decision(0, 1300 * MS)]
    assert outcomes == [Outcome.RIGHT, Outcome.DUPLICATE, Outcome.UNKNOWN_ID,
                        Outcome.WHILE_STOPPED, Outcome.LATE, Outcome.LATE]
    s = sb.summary(with_log=True)
    assert s["decisions"] == 6 == sum(s[o.value] for o in Outcome)
    assert (s["right"], s["duplicates"], s["unknown_id"], s["while_stopped"], s["late"]) == (
        1, 1, 1, 1, 2)
    assert (s["onsets"], s["matched"], s["misses"], s["pending"]) == (3, 1, 2, 0)
    assert s["accuracy"] == pytest.approx(1 / 3)
    assert s["latency_ms"] == {"p50": 40.0, "p99": 40.0}
    assert s["confusion"] == [[1, 1, 1]]
    assert [d["outcome"] for d in s["log"]] == [o.value for o in outcomes]
    assert s["log"][0] == {"t_us": 40 * MS, "stimulus_id": 1, "confidence": 0.9,
                           "token": None, "outcome": "right", "onset_us": 0, "true_id": 1}
    json.dumps(s)  # JSON-ready
    text = scoreboard_text(s)
    assert "6 decisions for 3 stimuli: 1 right, 0 wrong, 2 missed (accuracy 33.3 %)" in text
    assert "2 late, 1 duplicates, 0 false alarms, 1 while stopped, 1 unknown id" in text
    assert "no DECISION" in scoreboard_text(DecisionScoreboard(0.1).summary())
    with pytest.raises(ConfigError, match="response window"):
        DecisionScoreboard(0.0)


def _ack(peer: PtyPeer, token: int) -> protocols.Ack:
    assert peer.wait_for(lambda p: any(a.token == token for a in p.of(protocols.Ack)), 10)
    return next(a for a in peer.of(protocols.Ack) if a.token == token)


def _onset(peer: PtyPeer, stimulus_id: int) -> None:
    """Start ``stimulus_id`` now and wait for its ground-truth onset marker."""
    before = len(peer.of(protocols.Marker))
    token = peer.command(protocols.CommandCode.SET_STIMULUS, stimulus_id)
    assert _ack(peer, token).ok
    assert peer.wait_for(lambda p: any(
        m.stimulus_id == stimulus_id and m.phase == protocols.MarkerPhase.ONSET
        for m in p.of(protocols.Marker)[before:]), 10)


def test_scripted_dut_lands_in_every_counter(pty_pair, tmp_path: Path) -> None:
    window_s = 0.3
    score = tmp_path / "score.json"
    serve = ServeProcess("--port", pty_pair.path, "--host-driven", "--snr", "inf",
                         "--response-window", str(window_s), "--score", str(score),
                         "--truth", str(tmp_path / "truth.jsonl"), "--markers", "--json")
    peer = PtyPeer(pty_pair.master)
    try:
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 30)
        assert not serve.exited, serve.stderr
        tokens: dict[str, int] = {}
        _onset(peer, 0)
        tokens["right"] = peer.decision(0, 0.75)
        _ack(peer, tokens["right"])
        time.sleep(window_s + 0.2)
        tokens["false_alarm"] = peer.decision(5)  # long after a decided onset
        _onset(peer, 1)
        tokens["wrong"] = peer.decision(2)
        tokens["twice"] = peer.decision(1)
        _onset(peer, 3)
        time.sleep(window_s + 0.2)
        tokens["late"] = peer.decision(3)  # the onset is missed, its answer late
        tokens["unknown"] = peer.decision(9999)
        _onset(peer, 4)  # never answered: a miss
        time.sleep(window_s + 0.2)
        assert _ack(peer, peer.command(protocols.CommandCode.STOP)).ok
        tokens["stopped"] = peer.decision(4)
        acks = {name: _ack(peer, t) for name, t in tokens.items()}
        serve.interrupt()
        assert serve.wait(30) == 130, serve.stderr  # stopped cleanly by Ctrl-C
    finally:
        serve.kill()
        peer.close()
    refused = {name: a.reason for name, a in acks.items() if not a.ok}
    assert refused == {"unknown": protocols.NackReason.UNKNOWN_STIMULUS,
                       "stopped": protocols.NackReason.NOT_RUNNING}
    assert all(a.opcode == protocols.CommandCode.DECISION for a in acks.values())
    written = check_file("score", score)  # every outcome, against the score file's schema
    check_process_lines(serve.lines, "serve --json")
    truth = check_lines("truth-line", tmp_path / "truth.jsonl")
    assert [t["phase"] for t in truth if t["type"] == "marker"].count("onset") >= 1
    board = serve.summary()["scoreboard"]
    assert {k: v for k, v in written.items() if k not in ("log", "tasks")} == board
    assert written["tasks"] == {}  # no contacts: no contact task posed
    live = [x["scoreboard"] for x in serve.lines if x.get("type") == "status"]
    assert live and 1 <= live[-1]["decisions"] <= board["decisions"]
    counts = {k: board[k] for k in ("right", "wrong", "duplicates", "late", "false_alarms",
                                    "unknown_id", "while_stopped")}
    assert counts == {"right": 1, "wrong": 1, "duplicates": 1, "late": 1, "false_alarms": 1,
                      "unknown_id": 1, "while_stopped": 1}
    assert (board["decisions"], board["onsets"], board["matched"], board["misses"]) == (
        7, 4, 2, 2)
    assert board["accuracy"] == pytest.approx(1 / 4)
    assert board["confusion"] == [[0, 0, 1], [1, 2, 1]]
    assert 0 < board["latency_ms"]["p50"] <= window_s * 1000
    log = {d["outcome"]: d for d in written["log"]}
    assert {name: log[o]["token"] for name, o in (("right", "right"), ("twice", "duplicates"),
                                                  ("stopped", "while_stopped"))} == {
        name: tokens[name] for name in ("right", "twice", "stopped")}
    assert log["right"]["confidence"] == pytest.approx(0.75, abs=0.5 / 254)
    assert log["late"]["t_us"] - log["late"]["onset_us"] > window_s * 1e6


@pytest.mark.parametrize(("args", "says"), [
    (("--response-window", "0"), "response-window"),
    (("--response-window", "nan"), "response-window"),
    (("--score", "/nonexistent-folder/score.json"), "does not exist"),
])
def test_serve_refuses_bad_scoring_options(args: tuple[str, ...], says: str) -> None:
    res = run_serve("--port", "loop://", "--duration", "0.1", *args)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
    assert len(lines) == 1 and lines[0].startswith("skinhil: error: ") and says in lines[0]
