"""``skinhil bench --suite``: the report card of a suite run, as a user runs it.

Against the reference receiver (``listen --answer``) on the bench's own pty pair, one case at
one drawn seed: the card is written as Markdown, JSON (valid against its schema) and JUnit
XML, and the JSON's numbers are the board's score files' (the decoder's and, standing in for
a baseline, the same run's). Against a silent decoder on a pty of the test's (``--port``),
the case fails with the reason "the decoder sent nothing", in the card and in JUnit,
and scores 0 of the onsets of the DECISION scoreboard. A
campaign whose criteria are upper bounds alone fails when the decoder only pings the board
and answers nothing.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pytest
from harness.peers import PtyPeer
from harness.serve import REPO, RUN_DIR, serve_env
from junitparser import Failure, JUnitXml

import protocols
from skinhil.campaign.case_run import NO_ANSWER, SENT_NOTHING, silence
from skinhil.campaign.criteria import parse_criterion
from skinhil.campaign.interval import wilson_interval
from skinhil.campaign.report_card import build_card, counts
from skinhil.campaign.suite_run import SuiteRun, draw_seeds
from skinhil.cli import main
from skinhil.decoding.classifier import DirectionDecoder
from skinhil.decoding.model_file import save_decoder
from skinhil.receiver.training import feature_spec
from skinhil.suites import suite

SCHEMA = REPO / "skinhil" / "schemas" / "report-card.schema.json"
SUITE = "tactile-v1"
CASE = "force"
LENIENT = ["--max-lateness-ms", "5000"]
"""A loaded test machine's ticks run late: the card is what is tested, not the timing."""


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model of no skill in the receiver's layout (the card needs answers, not right
    ones)."""
    spec = feature_spec()
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    path = tmp_path_factory.mktemp("model") / "model.npz"
    save_decoder(DirectionDecoder(spec).fit(x, y), path)
    return path


def _bench(*args: str, timeout_s: float = 400) -> tuple[int, str, str]:
    proc = subprocess.run([sys.executable, "-m", "skinhil", "bench", "--quiet", *args],
                          cwd=RUN_DIR, env=serve_env(), text=True, capture_output=True,
                          stdin=subprocess.DEVNULL, timeout=timeout_s)
    return proc.returncode, proc.stdout, proc.stderr


def _card(out: Path) -> dict[str, Any]:
    card = json.loads((out / "report-card.json").read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text(encoding="utf-8"))
                                    ).validate(card)
    return card


def test_the_card_of_a_case_against_the_reference_receiver(model: Path, tmp_path: Path
                                                            ) -> None:
    out = tmp_path / "run"
    status, stdout, stderr = _bench("--suite", SUITE, "--case", CASE, "--seeds", "1",
                                    "--seed", "5", "--model", str(model), "--out", str(out),
                                    *LENIENT)
    card = _card(out)
    the_suite = suite(SUITE)
    assert card["suite"] == {"id": SUITE, "name": the_suite.name,
                             "version": the_suite.version}
    assert card["draw"]["seeds"] == draw_seeds(the_suite, 5, 1)  # --seed reproduces it
    (seed,) = card["draw"]["seeds"]
    assert seed in the_suite.evaluation_seeds
    (record,) = card["cases"]
    assert record["case"] == CASE and record["seed"] == seed, stderr
    score = json.loads((Path(record["folder"]) / "score.json").read_text(encoding="utf-8"))
    entry = card["tasks"][CASE]
    own = score["tasks"][CASE]
    (row,) = entry["seeds"]
    charged = own["trials"] + own["answers"] - own["matched"]
    assert row == {"seed": seed, "score": row["score"], "right": round(own["score"] * charged),
                   "charged": charged, "outcome": record["outcome"]}
    assert row["score"] == pytest.approx(own["score"], abs=1e-6)  # the score file's
    assert entry["charged"] == own["trials"] + own["answers"] - own["matched"] > 0
    assert entry["score"] == pytest.approx(own["score"], abs=1e-6)
    assert entry["interval"] == list(wilson_interval(entry["right"], entry["charged"]))
    assert own["answers"] > 0, stderr  # the reference receiver answered
    # Markdown and JUnit beside it
    md = (out / "report-card.md").read_text(encoding="utf-8")
    assert f"| {CASE} | {CASE} |" in md and str(seed) in md
    (junit_suite,) = list(JUnitXml.fromfile(str(out / "junit.xml")))
    assert [c.name for c in junit_suite] == [record["id"]]
    assert status == (0 if record["outcome"] == "passed" else 1), stdout
    # the baselines are pooled from their runs' score files alike
    decoder = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    again = build_card(the_suite, SuiteRun(decoder, {"reference": decoder}), 5, [seed], "x")
    base = again["tasks"][CASE]["baselines"]["reference"]
    assert {k: base[k] for k in ("score", "right", "charged")} == \
        {k: entry[k] for k in ("score", "right", "charged")}


def test_a_silent_decoders_case_fails_with_its_reason(tmp_path: Path, pty_pair: Any) -> None:
    """The classification case, whose score is the board's DECISION scoreboard (the score
    file's top level): a silent decoder scores 0 of its onsets."""
    peer = PtyPeer(pty_pair.master)  # reads the stream, sends nothing
    out = tmp_path / "run"
    try:
        status, _, stderr = _bench("--suite", SUITE, "--case", "classification", "--seeds",
                                   "1", "--port", pty_pair.path, "--out", str(out), *LENIENT)
    finally:
        peer.close()
    card = _card(out)
    (record,) = card["cases"]
    assert record["outcome"] == "failed", record
    assert record["message"] == SENT_NOTHING
    score = json.loads((Path(record["folder"]) / "score.json").read_text(encoding="utf-8"))
    entry = card["tasks"]["classification"]
    assert score["onsets"] > 0 and score["decisions"] == 0
    assert (entry["right"], entry["charged"], entry["score"]) == (0, score["onsets"], 0)
    (junit_suite,) = list(JUnitXml.fromfile(str(out / "junit.xml")))
    (case,) = list(junit_suite)
    (result,) = case.result
    assert isinstance(result, Failure) and result.message == SENT_NOTHING
    assert SENT_NOTHING in (out / "report-card.md").read_text(encoding="utf-8")
    assert status == 1, stderr


def test_upper_bounds_alone_need_an_answer(tmp_path: Path, pty_pair: Any) -> None:
    """A decoder that pings the board and answers nothing: ``false_alarms <= 2`` holds, and
    the case fails all the same."""
    campaign = tmp_path / "bounds.toml"
    campaign.write_text('name = "bounds"\ncriteria = ["false_alarms <= 2", "misses < 1000"]\n'
                        "[parameters]\nduration_s = 1.5\n[[scenario]]\nbuiltin = \"random\"\n"
                        "[rig]\nmax_lateness_ms = 5000.0\n", encoding="utf-8")
    peer = PtyPeer(pty_pair.master)
    stop = threading.Event()

    def ping() -> None:  # once the board streams: a PING, no answer
        if peer.wait_for(lambda p: len(p.events) > 0, 120) and not stop.is_set():
            peer.command(protocols.CommandCode.PING)

    pinger = threading.Thread(target=ping, daemon=True)
    pinger.start()
    out = tmp_path / "run"
    try:
        status, _, stderr = _bench(str(campaign), "--port", pty_pair.path, "--out", str(out))
    finally:
        stop.set()
        peer.close()
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    (record,) = summary["cases"]
    assert record["rig"]["board"]["commands"] >= 1, stderr
    assert all(v["holds"] for v in record["criteria"]), record
    if record["outcome"] != "error":  # a loaded machine's late tick is the rig's error
        assert record["outcome"] == "failed" and record["message"] == NO_ANSWER, record
        assert status == 1


def test_silence_rules() -> None:
    bounds = (parse_criterion("false_alarms <= 2", "t"),)
    mixed = bounds + (parse_criterion("decisions >= 0", "t"),)
    quiet = {"decisions": 0, "tasks": {"force": {"answers": 0}}}
    answered = {"decisions": 0, "tasks": {"force": {"answers": 1}}}
    assert silence({"commands": 0}, answered, ()) == [SENT_NOTHING]
    assert silence({"commands": 3}, quiet, bounds) == [NO_ANSWER]
    assert silence({"commands": 3}, answered, bounds) == []
    assert silence({"commands": 3}, quiet, mixed) == []
    assert silence({"commands": 3}, quiet, ()) == []


def test_wilson_interval() -> None:
    lo, hi = wilson_interval(0, 10)  # type: ignore[misc]
    assert lo == 0.0 < hi < 0.35
    lo, hi = wilson_interval(10, 10)  # type: ignore[misc]
    assert 0.65 < lo < hi == 1.0
    lo, hi = wilson_interval(5, 10)  # type: ignore[misc]
    assert lo < 0.5 < hi and 0.5 - lo == pytest.approx(hi - 0.5)
    assert wilson_interval(0, 0) is None


@pytest.mark.parametrize(("args", "word"), [
    (["--suite", "tactile-v9"], "no suite"),
    (["--suite", SUITE, "--case", "juggling"], "no case"),
    (["--suite", SUITE, "--seeds", "0"], "--seeds"),
    (["--suite", SUITE, "--resume"], "--seed N"),
    (["--suite", SUITE, "--port", "/dev/null", "--faults", "drop_p=0.1"], "--faults"),
    ([str(REPO / "examples" / "campaigns" / "smoke.toml"), "--suite", SUITE], "not both"),
    ([str(REPO / "examples" / "campaigns" / "smoke.toml"), "--seeds", "2"], "--suite"),
    ([], "--suite"),
])
def test_a_refused_suite_run_is_one_line(args: list[str], word: str, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    try:  # refused by the parser (SystemExit) or by the command (its status)
        status = main(["bench", *args, "--out", str(tmp_path / "out")])
    except SystemExit as exc:
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("skinhil: error: ") and "\n" not in err and word in err, err
    assert not (tmp_path / "out").exists()


def test_listen_grips_only_with_answer(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                       ) -> None:
    model = tmp_path / "m.npz"
    model.write_bytes(b"")
    assert main(["listen", "--port", "loop://", "--model", str(model), "--grip-readout",
                 str(model)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--grip-readout" in err and "--answer" in err, err


def test_pooled_counts_keep_each_tasks_own_rule() -> None:
    """A seed's right and charged reproduce its headline score: a hedged right answer counts
    for nothing, and a detection (SLIP) cancelled by unmatched answers counts nothing while
    its denominator stays the trials (a blind SLIP cadence pools to 0, not to right over
    every answer)."""
    slip = {"tasks": {"slip": {"score": 0.0, "right": 5, "trials": 5, "answers": 40,
                               "matched": 5}}}
    assert counts(slip, "slip") == (0, 5)
    slip["tasks"]["slip"].update(score=0.6, answers=7)  # 5 detections, 2 unmatched
    assert counts(slip, "slip") == (3, 5)
    force = {"tasks": {"force": {"score": 0.25, "right": 3, "trials": 6, "answers": 8,
                                 "matched": 6}}}  # one right answer hedged
    assert counts(force, "force") == (2, 8)
    decisions = {"score": 0.5, "right": 2, "onsets": 2, "decisions": 2, "matched": 2}
    assert counts(decisions, "classification") == (1, 2)
