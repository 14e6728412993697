"""``skinhil reproduce --quick``: every figure, every claim row (each mechanics with each
readout), the per-sensor table; and each claim rule on made-up numbers, one that must pass and
one that must fail."""

import json
import re
import time
from pathlib import Path

import numpy as np

from skinhil.analysis.information import InformationMeasures
from skinhil.analysis.sweep import SweepResult, SweepSpec
from skinhil.cli import main
from skinhil.decoding import CVResult
from skinhil.reproduce import FIGURES, claims
from skinhil.reproduce.report import CLAIM_KEYS, likely_cause

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
LABELS = ("linear/length", "linear/axial", "geometric/length", "geometric/axial")


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
                 "Mean per tercile block", "Baseline tension", "## linear mechanics, length",
                 "## geometric mechanics, axial", "Statistical error at 10 dB",
                 "## Regime", "Profile along damping"):
        assert text in report, text
    # one claims row per claim, mechanics and readout, each yes or no, with its figure
    rows = [line for line in report.splitlines()
            if re.match(r"\| (1E-F|2A|2B|2C|3F|4F|4G) \|", line)]
    assert [(r.split(" | ")[0][2:], f"{r.split(' | ')[2]}/{r.split(' | ')[3]}")
            for r in rows] == [(k, label) for k in CLAIM_KEYS for label in LABELS]
    assert all(r.split(" | ")[4] in ("yes", "**no**") and ".png](" in r for r in rows)
    for label in LABELS:
        m, ro = label.split("/")
        counts = re.search(rf"{label} \*\*(\d) of 7\*\*", report)
        assert counts is not None, label
        assert int(counts[1]) == sum(f"| {m} | {ro} | yes |" in r for r in rows)
    # a row not reproduced names its cause when a swap reproduces it
    for r in rows:
        cells = r.split(" | ")
        assert (cells[4] == "yes") == (cells[7] == "—"), r

    results = json.loads((tmp_path / "results.json").read_text())
    assert results["regime"]["relative_displacement"]["linear"]["A"]["ratio"] > 1
    for mech in LABELS:
        r = results[mech]
        focus = r["focus_sensors"]
        assert len(focus) == 10 and r["paper_sensor"] == sorted(focus)[4]
        # per-sensor table: ten rows (ranks 1..10, #5 marked), one accuracy per SNR
        m, ro = mech.split("/")
        section = report.split(f"## {m} mechanics, {ro} readout")[1].split("\n## ")[0]
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


def test_4g_accuracy_rising_with_snr_passes_flat_or_saturated_fails() -> None:
    snrs = (0.0, 10.0, 20.0, float("inf"))
    rising = [_cv(a) for a in (0.2, 0.5, 0.7, 0.8)]
    flat = [_cv(0.11) for _ in snrs]
    saturated = [_cv(1.0) for _ in snrs]
    sets = {"one": rising, "all": saturated}
    assert claims.decoding_rises_with_snr(snrs, sets, "one").reproduced
    assert not claims.decoding_rises_with_snr(snrs, sets, "all").reproduced
    assert not claims.decoding_rises_with_snr(snrs, {"one": flat}, "one").reproduced


def test_4f_needs_the_band_and_a_response_in_every_condition() -> None:
    at_10 = {"one": _cv(0.5), "all": _cv(0.99), "few": _cv(0.2)}
    responds = [3.0] * 9
    assert claims.decoding_at_operating_point(10.0, at_10, "one", responds).reproduced
    assert not claims.decoding_at_operating_point(10.0, at_10, "all", responds).reproduced
    assert not claims.decoding_at_operating_point(10.0, at_10, "few", responds).reproduced
    # in the band, but silent in six conditions: (3 + 1)/9 = 0.44 is not a reproduction
    silent_six = [0.0] * 6 + [5.0, 8.0, 12.0]
    at_10["trivial"] = _cv(4 / 9)
    verdict = claims.decoding_at_operating_point(10.0, at_10, "trivial", silent_six)
    assert not verdict.reproduced and "6 of 9 conditions" in verdict.reason
    assert "one 0.50 (in the band)" in claims.decoding_at_operating_point(
        10.0, at_10, "all", responds).evidence


def _measures(npc_ind: float, npc_post: float, area: float) -> InformationMeasures:
    return InformationMeasures(area=area, npc99_ind=npc_ind, npc99_post=npc_post,
                               npc_ratio=npc_ind / npc_post, sir_ind=2.0, sir_post=1.0,
                               sir_ratio=2.0)


def test_1ef_more_components_during_indentation() -> None:
    assert claims.information_phases(_measures(12, 6, 3.0)).reproduced
    fails = claims.information_phases(_measures(4, 9, -2.0))
    assert not fails.reproduced and "post-indentation" in fails.reason


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


def test_3f_pass_and_fail() -> None:
    names = list("ABCDE")
    sim = np.eye(5)
    sim[1, 2] = sim[2, 1] = 0.9
    assert claims.inputs_2_3_most_similar(sim, names).reproduced
    sim[0, 4] = sim[4, 0] = 0.95
    assert not claims.inputs_2_3_most_similar(sim, names).reproduced


def _sweep(values: dict[str, np.ndarray]) -> SweepResult:
    n_k, n_c = next(iter(values.values())).shape
    spec = SweepSpec(tuple(np.geomspace(5, 500, n_k)), tuple(np.geomspace(0.005, 0.5, n_c)))
    return SweepResult(spec, {k: v[None] for k, v in values.items()}, 0.0)


def _hill(n_k: int, n_c: int, c_peak: float, k_slope: float) -> np.ndarray:
    """A measure with a maximum in damping at grid index ``c_peak`` (outside the grid: no
    interior optimum) and rising along K with ``k_slope``."""
    c = np.arange(n_c)
    k = np.arange(n_k)
    return 2.0 - 0.05 * (c[None, :] - c_peak) ** 2 + k_slope * k[:, None]


def test_2b_2c_need_an_interior_optimum_in_damping_at_the_named_k() -> None:
    n = 9
    interior_low_k = _hill(n, n, 4.0, -0.1)  # peaks mid-grid in C, at the lowest K
    interior_high_k = _hill(n, n, 4.0, 0.1)
    rising_to_edge = _hill(n, n, 12.0, -0.1)  # keeps growing with C: no turn-over
    assert claims.npc_ratio_region(_sweep({"npc_ratio": interior_low_k})).reproduced
    assert not claims.npc_ratio_region(_sweep({"npc_ratio": interior_high_k})).reproduced
    edge = claims.npc_ratio_region(_sweep({"npc_ratio": rising_to_edge}))
    assert not edge.reproduced and "high end" in edge.reason
    assert claims.sir_ratio_region(_sweep({"sir_ratio": interior_high_k})).reproduced
    assert not claims.sir_ratio_region(_sweep({"sir_ratio": interior_low_k})).reproduced
    assert claims.edge_of_optimum(rising_to_edge) == "high"
    assert claims.edge_of_optimum(interior_low_k) is None


def test_ties_are_broken_by_the_middle_tied_index_not_the_grid_order() -> None:
    # small-integer ratios: a plateau over C indices 2..6 ties; the middle (4) wins
    plateau = np.array([1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 2.0, 1.5, 1.0])
    assert claims.peak_index(plateau) == 4
    assert claims.peak_index(plateau[::-1]) == 4
    tied_to_the_edge = np.array([1.0, 2.0, 2.0, 2.0])
    assert claims.peak_index(tied_to_the_edge) == 2  # the lower middle of 1..3
    values = np.tile(plateau, (6, 1))
    values[:2] += 0.5  # low K highest at every damping
    assert claims.npc_ratio_region(_sweep({"npc_ratio": values})).reproduced


def test_2a_flat_except_at_the_extremes_passes_varying_everywhere_fails() -> None:
    n = 10  # extremes: damping column 0-1, stiffness rows 8-9
    flat_but_edges = np.full((n, n), 1.0) + 0.01 * np.arange(n)[None, :]
    flat_but_edges[:, 0] = -3.0
    flat_but_edges[9, :] = 5.0
    assert claims.area_flat_except_extremes(_sweep({"area": flat_but_edges})).reproduced
    varies_inside = flat_but_edges.copy()
    varies_inside[4, 5] = 9.0  # the largest change away from the extremes
    fails = claims.area_flat_except_extremes(_sweep({"area": varies_inside}))
    assert not fails.reproduced and "away from the extremes" in fails.reason
    # an area that changes steadily with log C everywhere fails whatever the extremes do
    ramp = np.tile(np.linspace(-3.0, 3.0, n), (n, 1))
    assert not claims.area_flat_except_extremes(_sweep({"area": ramp})).reproduced


def test_the_cause_is_named_from_the_swap_that_reproduces() -> None:
    outcome = {("linear", "length"): True, ("linear", "axial"): False,
               ("geometric", "length"): True, ("geometric", "axial"): False}
    assert "readout" in likely_cause(outcome, "linear", "axial")
    assert likely_cause(outcome, "linear", "length") == ""
    outcome = {("linear", "length"): False, ("linear", "axial"): False,
               ("geometric", "length"): True, ("geometric", "axial"): True}
    assert likely_cause(outcome, "linear", "axial").startswith("the dynamics")
    outcome = dict.fromkeys(outcome, False)
    assert likely_cause(outcome, "linear", "length").startswith("neither")
