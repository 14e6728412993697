"""``skinhil reproduce --quick``: every figure as a valid PNG, REPORT.md with every measure."""

import json
import time
from pathlib import Path

import numpy as np

from skinhil.analysis.sweep import SweepResult, SweepSpec
from skinhil.cli import main
from skinhil.decoding import CVResult
from skinhil.reproduce import FIGURES, claims

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_quick_reproduce_writes_figures_and_report(tmp_path: Path) -> None:
    start = time.perf_counter()
    assert main(["reproduce", "--quick", "--out", str(tmp_path), "--no-progress"]) == 0
    print(f"reproduce --quick: {time.perf_counter() - start:.1f} s")  # timed by benchmarks
    for name in FIGURES:
        data = (tmp_path / name).read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 5000, name
    report = (tmp_path / "REPORT.md").read_text()
    for text in ("nPC for 99% variance", "signal-information ratio", "Area between the",
                 "Similarity across stimuli", "Confusion matrix", "| inf |",
                 "## linear mechanics", "## geometric mechanics", "npc_ratio", "sir_ratio"):
        assert text in report, text
    assert report.count("| yes |") + report.count("| **no** |") == 10
    results = json.loads((tmp_path / "results.json").read_text())
    for mech in ("linear", "geometric"):
        m = results[mech]["measures"]
        assert m["npc99_ind"] >= 1 and m["npc99_post"] >= 1
        assert len(results[mech]["decoding"]) == 7
        assert results[mech]["decoding"][-1]["accuracy"] > 0.5  # noise-free trials


def test_claim_checks_follow_their_thresholds() -> None:
    def cv(acc: float) -> CVResult:
        return CVResult(acc, 0.01, np.array([acc]), np.eye(9, dtype=np.int64),
                        np.arange(9), 5, 1)
    snrs = (0.0, 10.0, 20.0, float("inf"))
    rising = [cv(a) for a in (0.11, 0.2, 0.6, 1.0)]
    flat = [cv(0.11) for _ in snrs]
    assert claims.decoding_rises_with_snr(snrs, rising).reproduced
    assert not claims.decoding_rises_with_snr(snrs, flat).reproduced
    assert claims.decoding_above_chance(snrs, rising).reproduced
    assert not claims.decoding_above_chance(snrs, flat).reproduced
    names = list("ABCDE")
    assert claims.dissimilar_responses(np.eye(5), names).reproduced
    assert not claims.dissimilar_responses(np.ones((5, 5)), names).reproduced
    spec = SweepSpec((1.0, 2.0), (0.1, 0.2))
    const = {k: np.ones((1, 2, 2)) for k in ("area", "npc_ratio", "sir_ratio")}
    assert not claims.sweep_dependence(SweepResult(spec, const, 0.0)).reproduced
    varied = {k: np.arange(4.0).reshape(1, 2, 2) + 1 for k in const}
    assert claims.sweep_dependence(SweepResult(spec, varied, 0.0)).reproduced
