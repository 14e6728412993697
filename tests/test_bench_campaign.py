"""``skinhil bench``: the smoke campaign of examples/ against the reference receiver
(``listen --answer``) on the bench's own pty pair, as a user runs it.

On a clean link the JUnit XML (read back with junitparser) and the JSON summary agree case
for case: the press case fails its 5 ms latency criterion (the decoder's failure) and the
link's tap saw no damaged frame. On a fault-injected link (``--faults``: bytes corrupted on
the way to the decoder) every case is an error of the rig, never a failure of the decoder.
A run stopped by Ctrl-C after its first case leaves a valid partial summary and JUnit XML;
``--resume`` plays the rest only. The campaign file's refusals are one line each.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from harness.schemas import check_bench_out
from harness.serve import REPO, RUN_DIR, serve_env
from junitparser import Error, Failure, JUnitXml

from skinhil.campaign.criteria import MissingKey, parse_criterion
from skinhil.cli import main
from skinhil.cli.parser import build_parser
from skinhil.cli.transport_args import link_url, transport_argv
from skinhil.decoding.classifier import DirectionDecoder
from skinhil.decoding.model_file import save_decoder
from skinhil.process_output import READY, SUMMARY, last_record, records
from skinhil.receiver.training import feature_spec

SMOKE = REPO / "examples" / "campaigns" / "smoke.toml"
TASKS = REPO / "examples" / "campaigns" / "tasks.toml"
FAULTS = "corrupt_byte_p=0.01,seed=3"


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model of no skill, fitted on random features in the receiver's layout: the smoke
    campaign's criteria need answers, not right ones (the demo's model trains a minute)."""
    spec = feature_spec()
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    path = tmp_path_factory.mktemp("model") / "model.npz"
    save_decoder(DirectionDecoder(spec).fit(x, y), path)
    return path


def _bench(*args: str, campaign: Path = SMOKE) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "skinhil", "bench", str(campaign), "--quiet",
                             *args], cwd=RUN_DIR, env=serve_env(), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL)


def _finish(proc: subprocess.Popen[str], timeout_s: float = 300) -> tuple[int, str, str]:
    out, err = proc.communicate(timeout=timeout_s)
    return proc.returncode, out, err


def _read(out: Path) -> tuple[dict[str, Any], JUnitXml]:
    check_bench_out(out)  # the summary, score files and process lines match their schemas
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return summary, JUnitXml.fromfile(str(out / "junit.xml"))


def _junit_agrees(summary: dict[str, Any], xml: JUnitXml) -> None:
    """The JUnit XML holds the summary's cases, each with its outcome as a result."""
    suites = list(xml)
    assert len(suites) == 1 and suites[0].name == summary["campaign"]["name"]
    suite = suites[0]
    cases = list(suite)
    t = summary["totals"]
    assert (suite.tests, suite.failures, suite.errors) == (t["played"], t["failed"],
                                                          t["errors"])
    assert [c.name for c in cases] == [r["id"] for r in summary["cases"]]
    for case, record in zip(cases, summary["cases"], strict=True):
        kinds = [type(r) for r in case.result]
        assert kinds == {"passed": [], "failed": [Failure], "error": [Error]}[
            record["outcome"]], (case.name, kinds)
        if case.result:
            assert case.result[0].message == record["message"]


def test_smoke_campaign_on_a_clean_link(model: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    status, stdout, stderr = _finish(_bench("--model", str(model), "--out", str(out)))
    summary, xml = _read(out)
    _junit_agrees(summary, xml)
    assert summary["complete"] and summary["totals"]["played"] == 2, stderr
    random_case, press = summary["cases"]
    assert [random_case["scenario"], press["scenario"]] == ["random", "press"]
    for record in summary["cases"]:  # the bench's own link damaged nothing
        link = record["rig"]["link"]
        assert link["frames_ok"] > 100
        assert link["crc_errors"] == link["frames_lost"] == link["malformed"] == 0
        assert record["criteria"][0] == {"criterion": "decisions >= 1",
                                         "value": record["criteria"][0]["value"],
                                         "holds": record["criteria"][0]["value"] >= 1}
    for record in summary["cases"]:  # the runner read the processes' own lines, by type
        folder = Path(record["folder"])
        ready = last_record(records((folder / "decoder.out").read_text()), READY)
        assert ready is not None and ready["command"] == "listen", record
        assert ready["answer"] == "reference" and ready["link_up"], ready
        board = last_record(records((folder / "board.out").read_text()), SUMMARY)
        assert board is not None and record["rig"]["board"]["ticks"] == board["ticks"] > 0
    # nobody answers a touch within 5 ms: the decoder's failure, unless the rig erred
    assert press["outcome"] in ("failed", "error")
    if press["outcome"] == "failed":
        assert "latency_ms.p50 <= 5" in press["message"]
    # the random case's verdict depends on the machine: on a loaded one the receiver's
    # answers can arrive after the board's run ended (decisions 0, a failure)
    assert random_case["outcome"] in ("passed", "failed", "error")
    assert status == 1  # not every case passed
    assert "2 of 2 cases played" in stdout


def test_the_task_campaign_scores_a_task(model: Path, tmp_path: Path) -> None:
    """examples/campaigns/tasks.toml: its criteria read the score file's
    ``tasks.localisation`` keys, which the board writes (a missing key would be the rig's
    error); the reference receiver's answers are counted."""
    out = tmp_path / "run"
    status, _, stderr = _finish(_bench("--model", str(model), "--out", str(out),
                                       campaign=TASKS))
    summary, xml = _read(out)
    _junit_agrees(summary, xml)
    (record,) = summary["cases"]
    assert record["outcome"] in ("passed", "failed"), record["message"]
    answers, error = record["criteria"]
    assert answers["criterion"] == "tasks.localisation.answers >= 3"
    assert error["criterion"] == "tasks.localisation.median_error_mm <= 1.5"
    assert answers["value"] >= 1, stderr  # the receiver answered the presses
    assert status == (0 if record["outcome"] == "passed" else 1)


def test_faulty_link_is_the_rigs_error_and_resume_plays_the_rest(model: Path,
                                                                 tmp_path: Path) -> None:
    out = tmp_path / "run"
    proc = _bench("--model", str(model), "--out", str(out), "--faults", FAULTS)
    deadline = time.monotonic() + 240
    while not (out / "summary.json").exists() and proc.poll() is None:
        assert time.monotonic() < deadline
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)  # during the second case
    status, _, stderr = _finish(proc)
    assert status == 130, stderr
    partial, xml = _read(out)
    _junit_agrees(partial, xml)
    assert not partial["complete"] and partial["totals"]["played"] == 1
    first = partial["cases"][0]

    status, stdout, stderr = _finish(_bench("--model", str(model), "--out", str(out),
                                            "--faults", FAULTS, "--resume"))
    summary, xml = _read(out)
    _junit_agrees(summary, xml)
    assert summary["complete"] and summary["cases"][0] == first  # not played again
    assert "(1 in the earlier run)" in stdout
    assert summary["totals"]["errors"] == 2 and summary["totals"]["failed"] == 0
    for record in summary["cases"]:
        assert record["outcome"] == "error"
        assert "the link damaged or lost" in record["message"]
        assert record["rig"]["link"]["injected"]["corrupted"] > 0
        assert record["rig"]["link"]["crc_errors"] > 0
    for case in next(iter(xml)):
        assert case.result[0].type == "rig"
    assert status == 1


BAD_CAMPAIGNS = {
    "no scenario": ('name = "x"\n', "[[scenario]]"),
    "unknown key": ('name = "x"\nfoo = 1\n[[scenario]]\nbuiltin = "random"\n', "foo"),
    "bad criterion": ('name = "x"\ncriteria = ["accuracy => 1"]\n[[scenario]]\n'
                      'builtin = "random"\n', "PATH OP NUMBER"),
    "bad parameter": ('name = "x"\n[parameters]\nsnr_db = "loud"\n[[scenario]]\n'
                      'builtin = "random"\n', "snr_db"),
    "unknown parameter": ('name = "x"\n[parameters]\nbaud = 9600\n[[scenario]]\n'
                          'builtin = "random"\n', "baud"),
    "missing file": ('name = "x"\n[[scenario]]\nfile = "nope.toml"\n', "not found"),
    "file and builtin": ('name = "x"\n[[scenario]]\nfile = "a.toml"\nbuiltin = "random"\n',
                         "exactly one"),
    "bad rig bound": ('name = "x"\n[[scenario]]\nbuiltin = "random"\n[rig]\n'
                      'max_fifo_drops = -1\n', "max_fifo_drops"),
    "too many cases": ('name = "x"\nrepetitions = 1000\n[parameters]\nseed = '
                       f'{list(range(20))}\n[[scenario]]\nbuiltin = "random"\n', "split"),
}


@pytest.mark.parametrize("name", list(BAD_CAMPAIGNS))
def test_bad_campaign_is_one_line(name: str, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    text, word = BAD_CAMPAIGNS[name]
    path = tmp_path / "campaign.toml"
    path.write_text(text, encoding="utf-8")
    assert main(["bench", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("skinhil: error: ") and "\n" not in err and word in err, err
    assert not (tmp_path / "out").exists()


def test_criteria_read_any_number_of_the_score_file() -> None:
    score = {"accuracy": 0.75, "latency_ms": {"p50": None, "p99": 80},
             "tasks": {"localisation": {"median_error_mm": 2.5}}, "confusion": [[0, 2, 3]],
             "name": "x", "flag": True}
    rows = [("accuracy >= 0.8", 0.75, False), ("accuracy < 0.8", 0.75, True),
            ("latency_ms.p99 <= 80", 80.0, True), ("latency_ms.p50 <= 80", None, False),
            ("tasks.localisation.median_error_mm <= 3", 2.5, True),
            ("confusion.0.2 == 3", 3.0, True), ("accuracy != 0.75", 0.75, False)]
    for text, value, holds in rows:
        criterion = parse_criterion(text, "test")
        assert criterion.value(score) == value, text
        assert criterion.holds(criterion.value(score)) is holds, text
    for text in ("tasks.slip.misses == 0", "name >= 1", "flag == 1", "confusion.1.0 > 0"):
        with pytest.raises(MissingKey):
            parse_criterion(text, "test").value(score)


@pytest.mark.parametrize("link", [
    ["--port", "/dev/ttyUSB0", "--baud", "115200"],
    ["--udp", "192.168.1.20:5005", "--bitrate", "2000000"],
    ["--can", "can0", "--interface", "virtual", "--fd", "--bitrate", "500000",
     "--data-bitrate", "2000000"],
])
def test_the_link_given_to_bench_is_the_boards(link: list[str]) -> None:
    """Each case's ``serve`` gets the link options as ``bench`` was given them."""
    bench = build_parser("bench").parse_args(["bench", "c.toml", *link])
    argv = transport_argv(bench)
    serve = build_parser("serve").parse_args(["serve", *argv])
    url = str(link_url(serve))
    assert argv == ["--link", url]
    assert all(value in url for value in link if not value.startswith("--")), url
    assert transport_argv(serve) == argv


def test_a_board_that_cannot_start_is_the_rigs_error(tmp_path: Path) -> None:
    campaign = tmp_path / "one.toml"
    campaign.write_text('name = "one"\ncriteria = ["decisions >= 1"]\n[parameters]\n'
                        'duration_s = 1.0\n[[scenario]]\nbuiltin = "random"\n',
                        encoding="utf-8")
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "skinhil", "bench", str(campaign), "--quiet",
                           "--port", str(tmp_path / "no-such-tty"), "--out", str(out)],
                          cwd=RUN_DIR, env=serve_env(), text=True, capture_output=True,
                          timeout=120, stdin=subprocess.DEVNULL)
    assert done.returncode == 1, done.stderr
    summary, xml = _read(out)
    (record,) = summary["cases"]
    assert record["outcome"] == "error" and record["criteria"] == []
    assert "the board process ended with status 2: skinhil: error:" in record["message"]
    assert "no-such-tty" in record["message"]
    assert [type(r) for r in next(iter(next(iter(xml)))).result] == [Error]


def test_a_file_that_is_no_model_is_one_line(model: Path, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    broken = tmp_path / "broken.npz"
    broken.write_bytes(b"not a model")
    for path, word in ((broken, "not a decoder"), (tmp_path / "none.npz", "none.npz")):
        assert main(["bench", str(SMOKE), "--model", str(path), "--out",
                     str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("skinhil: error: ") and "\n" not in err and word in err, err
    assert not (tmp_path / "out").exists()
