"""The example decoder under test (``examples/dut_threshold.py``) against ``skinhil serve`` on
a pty pair (socat), as a user runs it: the board scores it well above chance at 10 dB.

The example needs nothing of skinhil but the ``protocols`` codecs (checked on its imports).
"""

from __future__ import annotations

import ast
import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from harness.serve import REPO, RUN_DIR, run_serve, serve_env

EXAMPLE = REPO / "examples" / "dut_threshold.py"
DURATION_S = 30.0
"""60 stimuli of the default random schedule (0.25 s each, 0.25 s rest)."""


def test_example_imports_only_the_codecs_and_the_links() -> None:
    tree = ast.parse(EXAMPLE.read_text(encoding="utf-8"))
    roots = {alias.name.split(".")[0] for node in ast.walk(tree)
             if isinstance(node, ast.Import) for alias in node.names}
    roots |= {(node.module or "").split(".")[0] for node in ast.walk(tree)
              if isinstance(node, ast.ImportFrom)}
    assert roots <= {"__future__", "argparse", "collections", "numpy", "protocols", "serial",
                     "can"}, roots


def test_example_dut_is_scored_above_chance_on_a_pty(tmp_path: Path) -> None:
    if shutil.which("socat") is None:
        pytest.skip("socat is not installed (apt-get install socat)")
    board_end, host_end = tmp_path / "ttyBOARD", tmp_path / "ttyHOST"
    socat = subprocess.Popen(["socat", f"pty,raw,echo=0,link={board_end}",
                              f"pty,raw,echo=0,link={host_end}"])
    dut = None
    score = tmp_path / "score.json"
    try:
        end = time.monotonic() + 10
        while not (board_end.exists() and host_end.exists()):
            assert time.monotonic() < end, "socat made no pty pair"
            time.sleep(0.05)
        dut = subprocess.Popen([sys.executable, str(EXAMPLE), "--port", str(host_end)],
                               cwd=RUN_DIR, env=serve_env(), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        board = run_serve("--port", str(board_end), "--duration", str(DURATION_S), "--seed",
                          "2", "--snr-db", "10", "--score", str(score), "--quiet",
                          timeout_s=DURATION_S + 60)
        assert board.returncode == 0, board.stderr
        dut.send_signal(signal.SIGINT)
        out, err = dut.communicate(timeout=10)
    finally:
        if dut is not None and dut.poll() is None:
            dut.kill()
        socat.kill()
    assert dut.returncode == 0, err
    s = json.loads(score.read_text())
    print(f"\nexample DUT: {s['decisions']} decisions for {s['onsets']} stimuli: {s['right']} "
          f"right, {s['wrong']} wrong, {s['misses']} missed, accuracy {s['accuracy']:.3f}, "
          f"latency p50 {s['latency_ms']['p50']} ms")
    decided = out.count("decided stimulus")
    assert decided == s["decisions"] > 0  # every answer it printed reached the board
    scored = s["matched"] + s["misses"]
    assert scored >= s["onsets"] - 1 >= 55
    # chance is 1/9: 13 right of ~60 is 2.7 standard deviations above it
    assert s["right"] >= 13 and s["accuracy"] > 2 / 9
    assert all(d["confidence"] is not None for d in s["log"])
