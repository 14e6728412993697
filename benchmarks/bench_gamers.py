"""The gamers' table (docs/suites.md, under "Baselines"): every scripted decoder that reads no
spike (``tests/harness/gamer_roster.py``: the gamers of ``tests/test_suite_gamers.py``, the
constant vibration classes, the blind grips) played on evaluation seeds of ``tactile-v1``
drawn at run time, beside the random answerer and (for the grasp) the reference grip
controller on the same seeds.

The seeds are drawn as ``skinhil bench --suite tactile-v1 --seed N --seeds K`` draws them
(:func:`skinhil.campaign.suite_run.draw_seeds`): the same ``--seed`` and ``--seeds`` give the
same evaluation seeds as the baselines table. One more seed is drawn after them; the replaying
gamers answer on each seed the truth of the next seed drawn. Every case is played off the
clock (``tests/harness/suite_play.py``: exact, every command at its tick) and scored by the
board; per gamer the score is pooled over the seeds (right and charged summed,
:func:`skinhil.campaign.report_card.pooled`) with its 95 % Wilson interval. A task's gamer is
at or below the random answerer when its pooled score is (a higher one within the random
answerer's 95 % interval is marked so); a blind grip when its
``grasp.score`` stays at least ``GRASP_MARGIN`` below the reference controller's.

It writes the figures through ``results.py`` (benchmarks/results/gamers.json: the
machine, the load, the command, the date), the table's data to
benchmarks/results/suite/bench_gamers.json, and renders the docs table from it between the
markers of docs/suites.md (never typed by hand); ``--render`` renders it from that file alone.

    python benchmarks/bench_gamers.py                 # 5 seeds drawn now
    python benchmarks/bench_gamers.py --seed 42       # the seeds --seed 42 draws
    python benchmarks/bench_gamers.py --render        # the docs table from the results file
    python benchmarks/bench_gamers.py --smoke         # one seed, a few gamers
"""

from __future__ import annotations

import argparse
import datetime
import json
import secrets
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "benchmarks")]

import results as bench_results  # noqa: E402
from bench_suite import keep_table, put_between  # noqa: E402
from harness import gamer_roster as roster  # noqa: E402
from harness.suite_play import Played  # noqa: E402
from machine import describe, load_average  # noqa: E402

from skinhil.campaign.report_card import GRASP, cell, counts, pooled  # noqa: E402
from skinhil.campaign.suite_run import draw_seeds  # noqa: E402
from skinhil.suites import registry  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "suite" / "bench_gamers.json"
"""The table's data per run, apart from the figure files the benchmarks page renders."""
DOCS = ROOT / "docs" / "suites.md"
BEGIN = "<!-- bench_gamers.py: begin -->"
END = "<!-- bench_gamers.py: end -->"
SEEDS = 5
SMOKE_GAMERS = ("force-constant", "localisation-replay")
SMOKE_GRIPPERS = ("maximum",)
REFERENCE = "reference grip controller"
RANDOM = "random answerer"

Play = Callable[[int, int], Played]
"""(evaluation seed, the next seed drawn) -> the played case."""


def pooled_score(played: list[Played], task: str) -> dict[str, Any]:
    """``task``'s score pooled over ``played`` (one run per seed) from their score files."""
    rows = []
    for p in played:
        c = counts(p.scores, task)
        if c is not None:
            rows.append({"right": c[0], "charged": c[1]})
    return pooled(rows)


def measure(gamers: dict[str, Play], grippers: dict[str, Play], seeds: list[int],
            others: list[int]) -> list[dict[str, Any]]:
    """One row per gamer and gripper: its case, its pooled score over ``seeds`` and the
    baseline it is held to (the random answerer, or the reference grip controller less
    ``GRASP_MARGIN``) over the same seeds, and whether it stays at or below it."""
    pairs = list(zip(seeds, others, strict=True))

    def over_seeds(play: Play) -> list[Played]:
        return [play(s, o) for s, o in pairs]

    rows: list[dict[str, Any]] = []
    randoms: dict[str, dict[str, Any]] = {}
    for name, play in gamers.items():
        case = roster.case_of(name)
        if case not in randoms:
            randoms[case] = pooled_score(
                over_seeds(lambda s, o, c=case: roster.random_answerer(c, s)), case)
        score = pooled_score(over_seeds(play), case)
        rows.append({"gamer": name, "case": case, **score, "baseline": RANDOM,
                     "baseline_score": randoms[case],
                     "at_or_below": _at_or_below(score, randoms[case], 0.0)})
    if grippers:
        reference = pooled_score(over_seeds(lambda s, o: roster.grasp_reference(s)), GRASP)
        for name, play in grippers.items():
            score = pooled_score(over_seeds(play), GRASP)
            rows.append({"gamer": f"grip {name}", "case": "grasp", **score,
                         "baseline": REFERENCE, "baseline_score": reference,
                         "at_or_below": _at_or_below(score, reference, roster.GRASP_MARGIN)})
    return rows


def _at_or_below(score: dict[str, Any], baseline: dict[str, Any], margin: float) -> bool | None:
    if score["score"] is None or baseline["score"] is None:
        return None
    return bool(score["score"] <= baseline["score"] - margin + 1e-12)


def figures(rows: list[dict[str, Any]], wall_s: float, per_seed_s: float) -> list[dict]:
    """The rows' scores and interval bounds as result figures, and the run's times."""
    out = [bench_results.figure("wall time of the run", round(wall_s, 1), "s"),
           bench_results.figure("wall time per seed", round(per_seed_s, 1), "s")]
    baselines = {(r["case"], r["baseline"]): r["baseline_score"] for r in rows}
    named = [(r["gamer"], r) for r in rows] + [
        (f"{case} {who}", b) for (case, who), b in baselines.items()]
    for name, e in named:
        if e["score"] is None:
            continue
        lo, hi = e["interval"]
        unit = f"score (right/charged, {e['right']}/{e['charged']})"
        out += [bench_results.figure(f"{name} score", round(e["score"], 4), unit),
                bench_results.figure(f"{name} 95 % low", round(lo, 4), unit),
                bench_results.figure(f"{name} 95 % high", round(hi, 4), unit)]
    return out


def _verdict(row: dict[str, Any]) -> str:
    """yes, or no; a task's no says whether the score lies within the random answerer's
    95 % interval (a difference the seeds played cannot tell from chance)."""
    if row["at_or_below"] is None:
        return "n/a"
    if row["at_or_below"]:
        return "yes"
    if row["baseline"] == REFERENCE:
        return f"**no** (within {roster.GRASP_MARGIN:g} of it)"
    hi = row["baseline_score"]["interval"][1]
    return "**no**, within its 95 % interval" if row["score"] <= hi else "**no**"


def table(results: dict[str, Any]) -> str:
    """The docs table of a results file."""
    out = [f"Measured by `{results['command']}` on {results['date']}: {results['machine']}; "
           f"{results['load']}. Suite {results['suite']}, seeds "
           f"{', '.join(map(str, results['seeds']))} (drawn with --seed {results['draw_seed']}"
           "; the replays answer the truth of the next seed drawn, the last one's "
           f"{results['others'][-1]}). Each score: pooled over the seeds [95 % Wilson "
           "interval] (right/charged). A blind grip is held to the reference grip "
           f"controller's `grasp.score` less {roster.GRASP_MARGIN:g}.", "",
           "| gamer | case | score | baseline, same seeds | at or below it |",
           "|---|---|---|---|---|"]
    for r in results["rows"]:
        base = f"{r['baseline']} {cell(r['baseline_score'])}"
        out.append(f"| {r['gamer']} | {r['case']} | {cell(r)} | {base} | {_verdict(r)} |")
    return "\n".join(out)


def render(results: dict[str, Any], docs: Path) -> None:
    """Put :func:`table` between the markers of ``docs``."""
    put_between(docs, BEGIN, END, table(results))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=SEEDS, help="evaluation seeds (default 5)")
    ap.add_argument("--seed", type=int, help="the draw's seed, as bench --suite --seed "
                                             "(default: drawn now)")
    ap.add_argument("--results", type=Path, default=RESULTS)
    ap.add_argument("--docs", type=Path, default=DOCS)
    ap.add_argument("--render", action="store_true",
                    help="render the docs table from --results, run nothing")
    ap.add_argument("--smoke", action="store_true",
                    help=f"one seed, the gamers {', '.join(SMOKE_GAMERS)} and the grip "
                         f"{', '.join(SMOKE_GRIPPERS)}; writes neither the results file nor "
                         "the docs")
    bench_results.add_arguments(ap)
    args = ap.parse_args()
    if args.render:
        render(json.loads(args.results.read_text(encoding="utf-8")), args.docs)
        print(f"rendered {args.docs} from {args.results}")
        return
    print(describe(), flush=True)
    suite = registry.suite(roster.SUITE)
    count = 1 if args.smoke else args.seeds
    draw_seed = args.seed if args.seed is not None else secrets.randbelow(2**31)
    drawn = draw_seeds(suite, draw_seed, count + 1)
    seeds, others = drawn[:count], drawn[1:]
    gamers: dict[str, Play] = {**roster.GAMERS, **roster.CONSTANT_CLASSES}
    grippers: dict[str, Play] = {n: (lambda s, o, f=f: f(s))
                                 for n, f in roster.GRIPPERS.items()}
    if args.smoke:
        gamers = {n: gamers[n] for n in SMOKE_GAMERS}
        grippers = {n: grippers[n] for n in SMOKE_GRIPPERS}
    load = load_average()
    t0 = time.monotonic()
    rows = measure(gamers, grippers, seeds, others)
    wall_s = time.monotonic() - t0
    machine = describe().splitlines()[0].removeprefix("machine: ")
    results = {"command": " ".join(["python", "benchmarks/bench_gamers.py", *sys.argv[1:]]),
               "date": datetime.date.today().isoformat(), "machine": machine,
               "load": f"{load} at the start, {load_average()} at the end",
               "suite": suite.id, "draw_seed": draw_seed, "seeds": seeds, "others": others,
               "wall_s": round(wall_s, 1), "rows": rows}
    print(table(results), flush=True)
    bench_results.publish(args, "gamers", "tactile-v1 gamers: scores and 95 % intervals "
                          "of decoders that read no spike, beside the random answerer and the "
                          "reference grip controller", figures(rows, wall_s, wall_s / count))
    if not args.smoke:
        keep_table(results, args.results, args.docs, render)


if __name__ == "__main__":
    main()
