"""``skinhil reproduce --quick``: every figure, every claim row, the per-sensor table; and the
claim checks against their rules on made-up numbers."""

import json
import re
import time
from pathlib import Path

import numpy as np

from skinhil.analysis.sweep import SweepResult, SweepSpec
from skinhil.cli import main
from skinhil.decoding import CVResult
from skinhil.reproduce import FIGURES, claims
from skinhil.reproduce.report import CLAIM_KEYS

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
MECHANICS = ("linear", "geometric")


def test_quick_reproduce_writes_figures_claims_and_sensor_table(tmp_path: Path) -> None:
    start = time.perf_counter()
    assert main(["reproduce", "--quick", "--out", str(tmp_path), "--no-progress"]) == 0
    print(f"reproduce --quick: {time.perf_counter() - start:.1f} s")  # timed by benchmarks
    for name in FIGURES:
        data = (tmp_path / name).read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 5000, name
    report = (tmp_path / "REPORT.md").read_text()
    for text in ("nPC for 99% variance", "signal-information ratio", "Area between the",
                 "Correlation index between the inputs", "Confusion matrix of sensor",
                 "Mean per tercile block", "Baseline tension", "## linear mechanics",
                 "## geometric mechanics", "Statistical error at 10 dB"):
        assert text in report, text
    # one claims row per claim and mechanics, each yes or no, with its figure
    rows = [line for line in report.splitlines()
            if re.match(r"\| (1E-F|2A|2B|2C|3F|4F|4G) \|", line)]
    assert [(r.split(" | ")[0][2:], r.split(" | ")[2]) for r in rows] == [
        (k, m) for k in CLAIM_KEYS for m in MECHANICS]
    assert all(r.split(" | ")[3] in ("yes", "**no**") and ".png](" in r for r in rows)
    counts = re.search(r"Claims reproduced: linear \*\*(\d) of 7\*\*, geometric \*\*(\d) of "
                       r"7\*\*", report)
    assert counts is not None
    assert int(counts[1]) == sum("| linear | yes |" in r for r in rows)
    assert int(counts[2]) == sum("| geometric | yes |" in r for r in rows)

    results = json.loads((tmp_path / "results.json").read_text())
    for mech in MECHANICS:
        r = results[mech]
        focus = r["focus_sensors"]
        assert len(focus) == 10 and r["paper_sensor"] == sorted(focus)[4]
        # per-sensor table: ten rows (ranks 1..10, #5 marked), one accuracy per SNR
        section = report.split(f"## {mech} mechanics")[1].split("\n## ")[0]
        table = [line for line in section.splitlines()
                 if re.match(r"\| (\*\*5\*\*|\d+) \| \d+ \| M\d+–M\d+ \|", line)]
        assert len(table) == 10 and "| **5** |" in table[4], table
        assert all(len(line.split(" | ")) == 3 + 7 + 1 for line in table)
        assert [int(line.split(" | ")[1]) for line in table] == focus
        # every feature set decoded at every SNR; noise-free trials decode above chance
        sets = r["decoding"]
        assert set(sets) == {f"sensor {s}" for s in focus} | {"M15's 10 sensors",
                                                               "all 338 sensors"}
        assert all(len(v) == 7 for v in sets.values())
        assert sets["all 338 sensors"][-1]["accuracy"] > 3 / 9
        assert [v["key"] for v in r["verdicts"]] == list(CLAIM_KEYS)
        assert np.asarray(r["tension_x_stiffness"]["area"]).shape[0] == 6
        sim = np.asarray(r["similarity"])
        assert np.all((sim >= 0) & (sim <= 1 + 1e-12)) and np.allclose(np.diag(sim), 1)


def _cv(acc: float) -> CVResult:
    return CVResult(acc, 0.01, np.array([acc]), np.eye(9, dtype=np.int64), np.arange(9), 5, 1)


def test_decoding_claims_follow_their_thresholds() -> None:
    snrs = (0.0, 10.0, 20.0, float("inf"))
    rising = [_cv(a) for a in (0.2, 0.5, 0.7, 0.8)]
    flat = [_cv(0.11) for _ in snrs]
    saturated = [_cv(1.0) for _ in snrs]
    sets = {"one": rising, "all": saturated}
    assert claims.decoding_rises_with_snr(snrs, sets, "one").reproduced
    assert not claims.decoding_rises_with_snr(snrs, sets, "all").reproduced
    assert not claims.decoding_rises_with_snr(snrs, {"one": flat}, "one").reproduced
    at_10 = {"one": _cv(0.5), "all": _cv(0.99), "few": _cv(0.2)}
    assert claims.decoding_at_operating_point(10.0, at_10, "one").reproduced
    assert not claims.decoding_at_operating_point(10.0, at_10, "all").reproduced
    assert not claims.decoding_at_operating_point(10.0, at_10, "few").reproduced
    assert "one 0.50 (in the band)" in claims.decoding_at_operating_point(
        10.0, at_10, "all").evidence


def test_similarity_claim_needs_inputs_2_3_strictly_most_similar() -> None:
    names = list("ABCDE")
    sim = np.eye(5)
    sim[1, 2] = sim[2, 1] = 0.9
    sim[0, 3] = sim[3, 0] = 0.5
    assert claims.inputs_2_3_most_similar(sim, names).reproduced
    sim[0, 3] = sim[3, 0] = 0.9  # a tie is not a reproduction
    assert not claims.inputs_2_3_most_similar(sim, names).reproduced
    sim[0, 3] = sim[3, 0] = 0.95
    assert not claims.inputs_2_3_most_similar(sim, names).reproduced


def _sweep(values: dict[str, np.ndarray]) -> SweepResult:
    n_k, n_c = next(iter(values.values())).shape
    spec = SweepSpec(tuple(np.geomspace(5, 500, n_k)), tuple(np.geomspace(0.005, 0.5, n_c)))
    return SweepResult(spec, {k: v[None] for k, v in values.items()}, 0.0)


def test_sweep_claims_name_the_tercile_block() -> None:
    n = 6  # terciles: rows/columns 0-1, 2-3, 4-5
    peak_low_k_mid_c = np.zeros((n, n))
    peak_low_k_mid_c[0:2, 2:4] = 2.0
    peak_high_k_mid_c = peak_low_k_mid_c[::-1].copy()
    assert claims.best_tercile(peak_low_k_mid_c) == ("low", "mid")
    assert claims.npc_ratio_region(_sweep({"npc_ratio": peak_low_k_mid_c})).reproduced
    assert not claims.npc_ratio_region(_sweep({"npc_ratio": peak_high_k_mid_c})).reproduced
    assert claims.sir_ratio_region(_sweep({"sir_ratio": peak_high_k_mid_c})).reproduced
    assert not claims.sir_ratio_region(_sweep({"sir_ratio": peak_low_k_mid_c})).reproduced
    assert claims.best_tercile(np.zeros((2, 2))) is None  # too small for terciles


def test_area_claim_excepts_only_the_extremes() -> None:
    n = 10  # extremes: damping column 0-1, stiffness rows 8-9
    flat_but_edges = np.full((n, n), 1.0)
    flat_but_edges[:, 0] = -3.0
    flat_but_edges[9, :] = 5.0
    assert claims.area_flat_except_extremes(_sweep({"area": flat_but_edges})).reproduced
    varies_inside = flat_but_edges.copy()
    varies_inside[4, 5] = 4.0
    assert not claims.area_flat_except_extremes(_sweep({"area": varies_inside})).reproduced
