"""The reference decoder in C (examples/skin_decoder.c), built with the system compiler:
it outputs what every conformance vector says (protocols/conformance.json), and against
``skinhil serve --score`` on a pair of ptys from ``skinhil pty`` it counts every event the
board's final STATUS says it sent, sees the RUN_END record and its DECISIONs are scored."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from harness.serve import REPO, RUN_DIR, run_serve, serve_env

import protocols

SOURCE = REPO / "examples" / "skin_decoder.c"
DURATION_S = 20.0
"""Board time of the live run (s): about 40 stimuli of the default random schedule."""


@pytest.fixture(scope="module")
def decoder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example built with the system C compiler, warnings as errors."""
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "no C compiler: apt-get install gcc (.ci/run does)"
    out = tmp_path_factory.mktemp("c") / "skin_decoder"
    subprocess.run([cc, "-std=c11", "-D_DEFAULT_SOURCE", "-O2", "-Wall", "-Wextra", "-Werror",
                    "-o", str(out), str(SOURCE), "-lm"], check=True, capture_output=True)
    return out


def _lines(text: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_c_decoder_outputs_every_conformance_vector(decoder: Path) -> None:
    doc = json.loads(protocols.CONFORMANCE_PATH.read_text(encoding="utf-8"))
    for case in doc["cases"]:
        run = subprocess.run([str(decoder), "--stdin"], input=bytes.fromhex(case["input"]),
                             capture_output=True, timeout=10, check=True)
        out = _lines(run.stdout.decode("utf-8"))
        assert [x["event"] for x in out if "event" in x] == case["events"], case["name"]
        assert [x["record"] for x in out if "record" in x] == case["records"], case["name"]
        assert out[-1] == {"counters": case["counters"]}, case["name"]


def test_c_decoder_against_serve_on_a_pty(decoder: Path, tmp_path: Path) -> None:
    score = tmp_path / "score.json"
    pty = subprocess.Popen([sys.executable, "-m", "skinhil", "pty", "--quiet"], cwd=RUN_DIR,
                           env=serve_env(), stdout=subprocess.PIPE, text=True)
    dut = None
    try:
        assert pty.stdout is not None
        board_end, host_end = pty.stdout.readline().strip(), pty.stdout.readline().strip()
        dut = subprocess.Popen([str(decoder), "--tty", host_end], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        board = run_serve("--port", board_end, "--duration", str(DURATION_S), "--seed", "3",
                          "--score", str(score), "--json", timeout_s=DURATION_S + 60)
        assert board.returncode == 0, board.stderr
        out, err = dut.communicate(timeout=20)  # it ends by itself at the RUN_END record
    finally:
        for p in (dut, pty):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    assert dut.returncode == 0, err
    got = _lines(out)[-1]
    summary = next(x for x in _lines(board.stdout) if x.get("type") == "summary")
    s = json.loads(score.read_text())
    c, status = got["counters"], got["status"]
    print(f"\nC decoder: {c['events_decoded']} events, status sent {status['events_sent']}, "
          f"{got['decisions']} decisions; board scored {s['decisions']} ({s['right']} right, "
          f"{s['wrong']} wrong, {s['misses']} missed)")
    # the same events as the board's final STATUS, none lost, nothing damaged
    assert c["events_decoded"] == status["events_sent"] == summary["sent"] > 5_000
    assert c["events_lost"] == 0 and c["crc_errors"] == c["malformed"] == c["seq_gaps"] == 0
    assert status["events_queued"] == 0 and status["t_us"] == DURATION_S * 1e6
    # the session configured it; the run's end came on the wire
    assert got["session"] == {"seen": 1, "n_channels": 338, "n_stimuli": 14,
                              "table_digest": got["session"]["table_digest"]}
    assert got["run_end"] == 1 and got["run_end_reason"] == int(protocols.RunEndReason.DURATION)
    # every DECISION it sent reached the board and was scored
    assert got["decisions"] == s["decisions"] >= 20
    assert s["matched"] + s["late"] + s["false_alarms"] + s["duplicates"] == s["decisions"]
    assert s["right"] > s["decisions"] / 9  # above chance (1 in 9)
