"""The example decoder under test (``examples/dut_threshold.py``) against ``skinhil serve`` on
a pty pair (socat), as a user runs it: the board scores it well above chance at 10 dB.

The example needs nothing of skinhil but the ``protocols`` codecs (checked on its imports).
"""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

from harness.host_link import host_beside_serve
from harness.serve import REPO

EXAMPLE = REPO / "examples" / "dut_threshold.py"
DURATION_S = 20.0
"""40 stimuli of the default random schedule (0.25 s each, 0.25 s rest)."""


def test_example_imports_only_the_codecs_and_the_links() -> None:
    tree = ast.parse(EXAMPLE.read_text(encoding="utf-8"))
    roots = {alias.name.split(".")[0] for node in ast.walk(tree)
             if isinstance(node, ast.Import) for alias in node.names}
    roots |= {(node.module or "").split(".")[0] for node in ast.walk(tree)
              if isinstance(node, ast.ImportFrom)}
    assert roots <= {"__future__", "argparse", "collections", "numpy", "protocols", "serial",
                     "can"}, roots


def test_example_dut_is_scored_above_chance_on_a_pty(tmp_path: Path) -> None:
    score = tmp_path / "score.json"
    board, dut = host_beside_serve(
        tmp_path, [sys.executable, str(EXAMPLE), "--port", "{HOST}"],
        ["--duration", str(DURATION_S), "--seed", "2", "--snr-db", "10", "--score", str(score),
         "--markers", "--quiet"], timeout_s=DURATION_S + 60, own_end_s=10.0)
    assert board.returncode == 0, board.stderr
    assert dut.returncode == 0, dut.stderr
    out = dut.stdout
    s = json.loads(score.read_text())
    print(f"\nexample DUT: {s['decisions']} decisions for {s['onsets']} stimuli: {s['right']} "
          f"right, {s['wrong']} wrong, {s['misses']} missed, accuracy {s['accuracy']:.3f}, "
          f"latency p50 {s['latency_ms']['p50']} ms")
    decided = out.count("decided stimulus")
    assert decided == s["decisions"] > 0  # every answer it printed reached the board
    scored = s["matched"] + s["misses"]
    assert scored >= s["onsets"] - 1 >= 35
    # chance is 1/9: 10 right of ~40 is 2.8 standard deviations above it
    assert s["right"] >= 10 and s["accuracy"] > 2 / 9
    assert all(d["confidence"] is not None for d in s["log"])
