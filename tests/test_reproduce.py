"""``skinhil reproduce --quick``: every figure, every claim row (each mechanics with each
readout), the per-sensor table; and each claim rule on made-up numbers, one that must pass and
one that must fail."""

import json
import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from skinhil.analysis import correlation, pca
from skinhil.analysis.information import InformationMeasures
from skinhil.analysis.sweep import SweepResult, SweepSpec
from skinhil.cli import main
from skinhil.decoding import CVResult
from skinhil.model import strain
from skinhil.model.skin import SkinParams
from skinhil.reproduce import FIGURES, claims
from skinhil.reproduce.report import CLAIM_KEYS, likely_cause

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
LABELS = tuple(f"{m}/{r}/paper" for m in ("linear", "geometric") for r in ("length", "axial"))
"""--quick runs the paper's amplitude only (the amplitude factor: the cause rule's test)."""


def test_quick_reproduce_writes_figures_claims_and_sensor_table(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    start = time.perf_counter()
    # the quick run on a 2 x 2 grid, one repeat: every figure, claim row and table of the
    # report (the whole --quick run is timed by benchmarks/bench_reproduce.py)
    assert main(["reproduce", "--quick", "--grid", "2", "--repeats", "1", "--workers", "2",
                 "--out", str(tmp_path), "--no-progress", "--json"]) == 0
    # --json: stdout is one JSON object naming the report, the figures and every verdict
    out = json.loads(capsys.readouterr().out)
    assert Path(out["report"]) == (tmp_path / "REPORT.md").resolve() and not out["search_only"]
    assert {Path(f).name for f in out["figures"]} >= {n for n in FIGURES if "_small" not in n}
    assert sorted(out["runs"]) == sorted(LABELS)
    assert all([v["claim"] for v in out["runs"][label]] == list(CLAIM_KEYS)
               and all(isinstance(v["reproduced"], bool) for v in out["runs"][label])
               for label in LABELS)
    print(f"reproduce --quick: {time.perf_counter() - start:.1f} s")  # timed by benchmarks
    for name in (n for n in FIGURES if "_small" not in n):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 5000, name
    report = (tmp_path / "REPORT.md").read_text()
    for text in ("nPC for 99% variance", "signal-information ratio", "Area between the",
                 "Correlation index between the inputs", "Confusion matrix of sensor",
                 "Mean per tercile block", "Baseline tension",
                 "## linear mechanics, length readout, paper amplitude",
                 "## geometric mechanics, axial readout, paper amplitude",
                 "Statistical error at 10 dB", "literal eq. 10 SIR", "## Where each claim holds",
                 "## The `paper` preset", "## Regime", "Profile along damping",
                 "fig4A_Fx0.5_Fy0.5"):
        assert text in report, text
    # one claims row per claim and run, each yes or no, with its strain and figure
    rows = [line for line in report.splitlines()
            if re.match(r"\| (1E-F|2A|2B|2C|3F|4F|4G) \|", line) and ".png](" in line]
    assert [(r.split(" | ")[0][2:], "/".join(r.split(" | ")[2:5])) for r in rows] == [
        (k, label) for k in CLAIM_KEYS for label in LABELS]
    assert all(r.split(" | ")[6] in ("yes", "**no**") and ".png](" in r for r in rows)
    assert all(re.fullmatch(r"[\d.]+% / [\d.]+%", r.split(" | ")[5]) for r in rows), rows[0]
    for label in LABELS:
        m, ro, a = label.split("/")
        counts = re.search(rf"{label} \*\*(\d) of 7\*\*", report)
        assert counts is not None, label
        assert int(counts[1]) == sum(r.split(" | ")[2:5] == [m, ro, a]
                                     and r.split(" | ")[6] == "yes" for r in rows)
    # a row not reproduced names its cause (or that no run reproduces it)
    for r in rows:
        cells = r.split(" | ")
        assert (cells[6] == "yes") == (cells[9] == "—"), r

    results = json.loads((tmp_path / "results.json").read_text())
    assert results["regime"]["relative_displacement"]["linear"]["A"]["ratio"] > 1
    assert results["paper_search"]["settings"] > 0
    for mech in LABELS:
        r = results[mech]
        assert r["strain"]["inputs"]["max"] >= r["strain"]["inputs"]["median"] > 0
        focus = r["focus_sensors"]
        assert len(focus) == 10 and r["paper_sensor"] == sorted(focus)[4]
        # per-sensor table: ten rows (ranks 1..10, #5 marked), one accuracy per SNR
        m, ro, a = mech.split("/")
        section = report.split(f"## {m} mechanics, {ro} readout, {a} amplitude")[1].split(
            "\n## ")[0]
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
        if a == "paper":
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


def test_1ef_more_components_during_indentation_with_the_papers_area_sign() -> None:
    # the paper's sign: area = sum(c_ind - c_post), negative when the indentation needs more
    assert claims.information_phases(_measures(12, 6, -3.0)).reproduced
    fails = claims.information_phases(_measures(4, 9, 2.0))
    assert not fails.reproduced and "post-indentation" in fails.reason
    assert not claims.information_phases(_measures(12, 6, 3.0)).reproduced
    # judged on stimulus 1; the stacked measures are shown, never judged
    v = claims.information_phases(_measures(12, 6, -3.0), stacked=_measures(4, 9, 2.0))
    assert v.reproduced and "stacked (extra): nPC99 4 vs 9" in v.evidence


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


def _two_maps(npc_k_slope: float, sir_k_slope: float, c_peak: float = 4.0,
              n: int = 9) -> SweepResult:
    return _sweep({"npc_ratio": _hill(n, n, c_peak, npc_k_slope),
                   "sir_ratio": _hill(n, n, 4.0, sir_k_slope)})


def test_2b_2c_turn_over_in_damping_and_lie_relative_to_each_other() -> None:
    # the paper's picture: both peak mid-damping, the nPC ratio at low K, the SIR at high K
    paper = _two_maps(-0.1, 0.1)
    assert claims.npc_ratio_region(paper).reproduced
    assert claims.sir_ratio_region(paper).reproduced
    # swapped in K: each optimum on the wrong side of the other
    swapped = _two_maps(0.1, -0.1)
    for verdict in (claims.npc_ratio_region(swapped), claims.sir_ratio_region(swapped)):
        assert not verdict.reproduced and "does not lie at" in verdict.reason
    # the nPC ratio still rising at the high-damping end: no intermediate optimum
    edge = claims.npc_ratio_region(_two_maps(-0.1, 0.1, c_peak=12.0))
    assert not edge.reproduced and "does not turn over" in edge.reason
    assert claims.edge_of_optimum(_hill(9, 9, 12.0, -0.1)) == "high"
    assert claims.edge_of_optimum(_hill(9, 9, 4.0, -0.1)) is None
    # both at the same K: neither lies lower or higher
    same = _two_maps(-0.1, -0.1)
    assert not claims.npc_ratio_region(same).reproduced
    assert not claims.sir_ratio_region(same).reproduced


def test_2b_2c_do_not_depend_on_tie_order_or_grid_order() -> None:
    # a plateau of exactly tied values (small-integer nPC ratios): the optimum is the set's
    # centroid, so reversing the grid mirrors the optimum and keeps every verdict
    plateau = np.array([1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 2.0, 1.5, 1.0])
    npc = np.tile(plateau, (9, 1)) + np.where(np.arange(9) < 3, 0.5, 0.0)[:, None]
    sir = np.tile(plateau, (9, 1)) + np.where(np.arange(9) > 5, 0.5, 0.0)[:, None]
    grid = _sweep({"npc_ratio": npc, "sir_ratio": sir})
    flipped = _sweep({"npc_ratio": npc[:, ::-1], "sir_ratio": sir[:, ::-1]})
    for sw in (grid, flipped):
        assert claims.npc_ratio_region(sw).reproduced
        assert claims.sir_ratio_region(sw).reproduced
    ks, cs = grid.spec.stiffness_n_per_m, grid.spec.damping_n_s_per_m
    loc = claims.optimum_location(npc, ks, cs)
    assert loc is not None and loc[1] == pytest.approx(np.mean(np.log10(cs)[2:7]))
    # a plateau that reaches the grid's end does not turn over, whatever the tie order
    to_edge = np.tile(np.array([1.0, 1.5, 2.0, 2.0, 2.0]), (9, 1))
    assert min(claims.turnover(to_edge)) == 0.0
    assert min(claims.turnover(to_edge[:, ::-1])) == 0.0


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
    runs = [(m, r, a) for m in ("linear", "geometric") for r in ("length", "axial")
            for a in ("paper", "small")]
    # reproduced with the length readout only
    outcome = {c: c[1] == "length" for c in runs}
    assert likely_cause(outcome, ("linear", "axial", "paper")).startswith("the readout")
    assert likely_cause(outcome, ("linear", "length", "paper")) == ""
    # reproduced at the paper's amplitude by the geometric dynamics only
    outcome = {c: c[0] == "geometric" and c[2] == "paper" for c in runs}
    assert likely_cause(outcome, ("linear", "axial", "paper")).startswith("the dynamics")
    assert likely_cause(outcome, ("geometric", "axial", "small")).startswith("the amplitude")
    assert likely_cause(outcome, ("linear", "axial", "small")).startswith(
        "only together: the dynamics and amplitude")
    outcome = dict.fromkeys(runs, False)
    assert likely_cause(outcome, ("linear", "length", "paper")).startswith("none")


def test_per_sensor_and_pooled_similarity_differ_where_the_paper_says() -> None:
    t = np.linspace(0, 1, 200)[:, None]
    shape = np.exp(-5 * t) * np.ones((1, 4))
    a = shape * np.array([1.0, 0.01, 0.01, 0.01])  # one loaded sensor
    b = shape * np.array([0.01, 1.0, 0.01, 0.01])  # another one: same time course
    # per sensor every trace has the same shape: index 1; pooled: the loads differ, ~0
    assert correlation.per_sensor_index(a, b) == pytest.approx(1.0)
    assert correlation.correlation_index(a, b) < 0.05
    c = np.sin(40 * t) * np.ones((1, 4))  # another time course altogether
    assert correlation.per_sensor_index(a, c) < 0.3
    sim = correlation.similarity_matrix_per_sensor(np.stack([a, b, c]))
    assert sim.shape == (3, 3) and np.allclose(np.diag(sim), 1)


def test_literal_sir_is_low_for_a_score_ringing_about_zero() -> None:
    t = np.linspace(0, 1, 400)
    ringing = np.stack([np.sin(60 * t) * np.exp(-t)] * 3, axis=1) + 1e-3 * t[:, None]
    sustained = np.stack([1 + 0.1 * np.sin(60 * t)] * 3, axis=1)
    # the project's reading (mean|z|/std) finds the ringing informative; eq. 10 read
    # literally (|mean z|/std) does not; both agree on a sustained score
    assert pca.signal_information_ratio(ringing) > 0.5
    assert pca.signal_information_ratio_literal(ringing) < 0.1
    assert pca.signal_information_ratio_literal(sustained) > 5
    assert pca.signal_information_ratio(sustained) > 5


def test_strain_summary_max_and_median_of_the_springs_peaks() -> None:
    params = SkinParams()
    rest = strain.rest_lengths_of(params)
    k = params.stiffness_n_per_m
    forces = np.zeros((2, 3, rest.size))
    forces[0, 1] = 0.1 * k * rest  # every spring 10 % in run 0
    forces[1, 2, 7] = -2.0 * k * rest[7]  # one spring compressed by 200 % in run 1
    st = strain.strain_summary(forces, params)
    assert st.max == pytest.approx(2.0)
    # median over the 2 x 338 (run, spring) peaks: 338 at 0.1, 337 at 0, one at 2.0
    assert st.median == pytest.approx(0.1)
    forces[0, 1, :200] = 0.0  # now 138 at 0.1, 537 at 0: the typical spring is unstrained
    assert strain.strain_summary(forces, params).median == 0.0
    scaled = strain.strain_summary(forces, replace(params, stiffness_n_per_m=10 * k))
    assert scaled.max == pytest.approx(0.2)


def test_the_search_section_names_what_no_setting_reproduces() -> None:
    from skinhil.reproduce.paper_search import SEARCH_CLAIMS, search_lines

    stage = {"stage": "coarse", "indentation_s": 0.05, "decay_tau_s": "inf", "post_factor": 1.0,
             "points_reproducing": {"1E-F": 3, "3F": 0, "4F response": 0},
             "map_verdicts": {k: {"reproduced": k == "2A"} for k in ("2A", "2B", "2C")},
             "best": {"stiffness_n_per_m": 50.0, "damping_n_s_per_m": 0.05,
                      "claims": ["1E-F", "2A"], "one_npc99": [3, 2], "one_area": -0.2,
                      "sim23": 0.1, "sim_other": 0.9, "min_spikes": 0, "strain_max": 2.0},
             "best_score": 2, "points": 4, "one_npc_ratio_range": [0.5, 1.5]}
    search = {"space": {"stiffness_range": [5, 500], "damping_range": [0.005, 0.5],
                        "n_coarse": 2, "indentation_s": [0.05], "decay_tau_s": ["inf"],
                        "post_factor": [1.0], "refine_best": 0, "refine_points": 3,
                        "mass_kg": 1e-4},
              "settings": 4, "seconds": 0.1, "stages": [stage], "best": stage,
              "reproduced_somewhere": {k: k in ("1E-F", "2A") for k in SEARCH_CLAIMS}}
    text = "\n".join(search_lines(search))
    assert "No linear setting searched reproduces: 2B, 2C, 3F, 4F response." in text
    assert "| 1E-F | yes | 3 of 4 |" in text and "| 3F | **no** | 0 of 4 |" in text
