"""``skinhil bench --suite --baselines`` on the bench's own pty pair: the reference, random
and oracle answerers' scores are on the report card beside the decoder's, each with its
interval, and no case is the rig's error, even when the model file the run was given is
removed while it plays (as the shared cache removes the files of another checkout's sources):
the run reads its own copies in ``OUT/inputs``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from harness.serve import RUN_DIR, serve_env

from skinhil.campaign.suite_run import BASELINES, INPUTS_NAME, baseline_folder
from skinhil.decoding.classifier import DirectionDecoder
from skinhil.decoding.model_file import save_decoder
from skinhil.receiver.training import feature_spec

CASE = "grasp"
"""The case that holds an object: every answerer's listener loads the model, the reference's
the grip readout too."""
TIMEOUT_S = 400.0


def _no_skill_model(path: Path) -> None:
    spec = feature_spec()
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    save_decoder(DirectionDecoder(spec).fit(x, y), path)


def _wait_for(path: Path, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not path.exists():
        assert proc.poll() is None, "the bench ended before copying its inputs"
        assert time.monotonic() < deadline, f"no {path} after {TIMEOUT_S} s"
        time.sleep(0.05)


def test_baselines_score_on_the_card_with_no_rig_error(tmp_path: Path) -> None:
    model = tmp_path / "model.npz"
    _no_skill_model(model)
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "skinhil", "bench", "--quiet", "--suite",
                             "tactile-v1", "--case", CASE, "--seeds", "1", "--seed", "7",
                             "--baselines", "--model", str(model), "--out", str(out),
                             "--max-lateness-ms", "5000"],
                            cwd=RUN_DIR, env=serve_env(), text=True, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        _wait_for(out / INPUTS_NAME / model.name, proc)
        model.unlink()  # the file given goes away under the run
        stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    card: dict[str, Any] = json.loads((out / "report-card.json").read_text(encoding="utf-8"))
    assert card["baselines"] == list(BASELINES), stderr
    assert card["complete"], stderr
    entry = card["grasp"]
    assert entry["interval"] is not None and entry["charged"] > 0, entry
    for name in BASELINES:
        base = entry["baselines"][name]
        assert base["charged"] == entry["charged"] > 0, (name, base)
        if name == "reference":  # the grip controller: the grasp's one baseline
            lo, hi = base["interval"]
            assert 0.0 <= lo <= base["score"] <= hi <= 1.0, (name, base)
        else:  # random and oracle send no GRIP: no baseline of the grasp
            assert base["score"] is None and base["interval"] is None, (name, base)
        summary = json.loads((baseline_folder(out, name) / "summary.json")
                             .read_text(encoding="utf-8"))
        errors = [r for r in summary["cases"] if r["outcome"] == "error"]
        assert not errors and summary["totals"]["played"] == 1, (name, errors)
    assert [r["outcome"] for r in card["cases"]] != ["error"], card["cases"]
    readouts = list((out / INPUTS_NAME).glob("grip-readout-*.npz"))
    assert len(readouts) == 1, list((out / INPUTS_NAME).iterdir())
    assert proc.returncode in (0, 1), stdout  # 1: a case the decoder failed, not a refusal
