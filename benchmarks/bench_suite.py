"""The suite's baselines table (docs/suites.md, "Baselines"): ``skinhil bench --suite
tactile-v1 --baselines`` on seeds drawn at run time, the reference receiver as the decoder on
the bench's own pty pair, the reference, random and oracle answerers (and the grasp's
reference controller) beside it at the same seeds.

It writes each task's scores (the decoder's and every baseline's, with their 95 % intervals)
as a benchmark result through ``results.py`` (benchmarks/results/suite.json: the
machine, the load, the command, the date), the whole report card to
benchmarks/results/suite/bench_suite.json, and renders the docs table from the card between
the markers of docs/suites.md (never typed by hand). One seed of every case with the
baselines plays 6 cases x 4 answerers, each a few seconds of board time and the start of a
board and a listener. ``--render`` renders the table from the
results file alone. The full run plays 6 cases x 5 seeds x 4 answerers in real time: run it on
a quiet machine (``nice``).

    python benchmarks/bench_suite.py                 # 5 seeds drawn now, every case
    python benchmarks/bench_suite.py --seed 42       # the seeds --seed 42 draws
    python benchmarks/bench_suite.py --render        # the docs table from the results file
    python benchmarks/bench_suite.py --smoke         # one case, one seed, no baselines
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import secrets
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results as bench_results  # noqa: E402
from machine import describe, load_average  # noqa: E402

from skinhil.campaign.report_card import cell  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "suite" / "bench_suite.json"
"""A report card per run, apart from the figure files the benchmarks page renders."""
DOCS = REPO / "docs" / "suites.md"
BEGIN = "<!-- bench_suite.py: begin -->"
END = "<!-- bench_suite.py: end -->"
SUITE = "tactile-v1"
SEEDS = 5
MAX_LATENESS_MS = 200.0
"""The rig's lateness bound of this run: a tick later than this makes its case an error."""


def quick_model(path: Path) -> None:
    """A classification model of no skill (the smoke run needs answers, not right ones)."""
    sys.path.insert(0, str(REPO))
    import numpy as np

    from skinhil.decoding.classifier import DirectionDecoder
    from skinhil.decoding.model_file import save_decoder
    from skinhil.receiver.training import feature_spec

    spec = feature_spec()
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    save_decoder(DirectionDecoder(spec).fit(x, y), path)


def figures(card: dict, wall_s: float) -> list[dict]:
    """The card's scores as result figures: per task, the decoder's and each baseline's score
    and 95 % interval bounds (a score n/a is left out), and the run's wall time."""
    rows = list(card["tasks"].items()) + ([("grasp", card["grasp"])] if "grasp" in card else [])
    out = [bench_results.figure("wall time of the bench run", wall_s, "s")]
    for task, entry in rows:
        who = [("decoder", entry), *((w, entry["baselines"].get(w)) for w in card["baselines"])]
        for name, e in who:
            if e is None or e["score"] is None:
                continue
            lo, hi = e["interval"]
            unit = f"score (right/charged, {e['right']}/{e['charged']})"
            out += [bench_results.figure(f"{task} {name} score", round(e["score"], 4), unit),
                    bench_results.figure(f"{task} {name} 95 % low", round(lo, 4), unit),
                    bench_results.figure(f"{task} {name} 95 % high", round(hi, 4), unit)]
    return out


def table(results: dict) -> str:
    """The docs table of a results file."""
    card = results["card"]
    who = card["baselines"]
    rows = list(card["tasks"].items()) + ([("grasp", card["grasp"])] if "grasp" in card else [])
    out = [f"Measured by `{results['command']}` on {results['date']}: {results['machine']}; "
           f"{results['load']}. Suite {card['suite']['id']}, skinhil "
           f"{card['versions']['skinhil']}, seeds {', '.join(map(str, card['draw']['seeds']))} "
           f"(drawn with --seed {card['draw']['seed']}). Each cell: the score pooled over the "
           "seeds [95 % Wilson interval] (right/charged); the decoder is the reference "
           "receiver on the bench's own link; n/a: the baseline answers no such trial. "
           f"Cases: {card['totals']['passed']} of {card['totals']['cases']} passed, "
           f"{card['totals']['errors']} errors of the rig.", "",
           "| " + " | ".join(["task", "decoder (reference receiver)", *who]) + " |",
           "|---|---|" + "---|" * len(who)]
    for name, e in rows:
        cells = [name, cell(e), *(cell(e["baselines"].get(w)) for w in who)]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def put_between(docs: Path, begin: str, end: str, text: str) -> None:
    """Put ``text`` between the markers ``begin`` and ``end`` of ``docs``."""
    page = docs.read_text(encoding="utf-8")
    pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    if not pattern.search(page):
        raise SystemExit(f"{docs} has no {begin} ... {end} markers")
    docs.write_text(pattern.sub(lambda _: f"{begin}\n{text}\n{end}", page), encoding="utf-8")


def keep_table(results: dict, path: Path, docs: Path, render: Callable[[dict, Path], None]
               ) -> None:
    """Write ``results`` to ``path`` and ``render`` its table into ``docs``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    render(results, docs)
    print(f"wrote {path} and the table of {docs}")


def render(results: dict, docs: Path) -> None:
    """Put :func:`table` between the markers of ``docs``."""
    put_between(docs, BEGIN, END, table(results))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=SEEDS)
    ap.add_argument("--seed", type=int, help="bench --seed (default: drawn now)")
    ap.add_argument("--results", type=Path, default=RESULTS)
    ap.add_argument("--docs", type=Path, default=DOCS)
    ap.add_argument("--render", action="store_true",
                    help="render the docs table from --results, run nothing")
    ap.add_argument("--smoke", action="store_true",
                    help="the force case, one seed, no baselines, a model of no skill; "
                         "writes neither the results file nor the docs")
    bench_results.add_arguments(ap)
    args = ap.parse_args()
    if args.render:
        render(json.loads(args.results.read_text(encoding="utf-8")), args.docs)
        print(f"rendered {args.docs} from {args.results}")
        return
    print(describe(), flush=True)
    seed = args.seed if args.seed is not None else secrets.randbelow(2**31)
    with tempfile.TemporaryDirectory(prefix="skinhil-suite-") as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "skinhil", "bench", "--suite", SUITE, "--seed", str(seed),
               "--out", str(out), "--quiet", "--max-lateness-ms", f"{MAX_LATENESS_MS:g}"]
        if args.smoke:
            model = Path(tmp) / "model.npz"
            quick_model(model)
            cmd += ["--case", "force", "--seeds", "1", "--model", str(model)]
        else:
            cmd += ["--seeds", str(args.seeds), "--baselines"]
        load = load_average()
        t0 = time.monotonic()
        proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, text=True, capture_output=True,
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(
                                  [str(REPO), os.environ.get("PYTHONPATH", "")])})
        wall_s = time.monotonic() - t0
        card_path = out / "report-card.json"
        if not card_path.exists():
            raise SystemExit(f"bench wrote no card (status {proc.returncode}):\n"
                             f"{proc.stderr[-2000:]}")
        card = json.loads(card_path.read_text(encoding="utf-8"))
    machine = describe().splitlines()[0].removeprefix("machine: ")
    results = {"command": " ".join(["python", "benchmarks/bench_suite.py", *sys.argv[1:]]),
               "bench": " ".join(["skinhil", *cmd[3:]]).replace(str(out), "OUT"),
               "date": datetime.date.today().isoformat(), "machine": machine,
               "load": f"{load} at the start, {load_average()} at the end",
               "wall_s": round(wall_s, 1), "card": card}
    print(table(results), flush=True)
    bench_results.publish(args, "suite", "tactile-v1 report card: scores and 95 % "
                          "intervals per task and answerer", figures(card, round(wall_s, 1)))
    if not args.smoke:
        keep_table(results, args.results, args.docs, render)


if __name__ == "__main__":
    main()
