"""The README's task table: per contact task, the board's score of the reference receiver,
of a random answerer and of the oracle (the truth through the same link).

For each task scenario (examples/scenarios/task_*.toml) it runs ``skinhil serve --score
--truth`` on one end of a socat pty pair and ``skinhil listen --answer --answer-with WHO`` on
the other: first the reference (its run's truth file feeds the oracle; the world's mechanics
do not depend on the noise, so every run of a scenario has the same truth), then random,
then oracle. Prints a markdown table and writes the scores as JSON.

    python benchmarks/bench_tasks.py --snr-db 10 [--tasks force,slip] [--out scores.json]
                                                    [--results-dir DIR]
    python benchmarks/bench_tasks.py --smoke    # one task, the reference, 1.5 s of board time
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, os.path.dirname(__file__))
from machine import describe  # noqa: E402
from results import add_arguments, figure, publish  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
TASKS = ("localisation", "force", "slip", "vibration")
WHO = ("reference", "random", "oracle")
SMOKE_DURATION_S = 1.5
"""--smoke: board time (s) of the scenario played, before the last answers' 0.6 s."""
METRIC = {"localisation": ("median_error_mm", "mm"), "force": ("median_error_n", "N"),
          "slip": ("latency_ms", "ms"), "vibration": ("median_error_hz", "Hz")}


@contextlib.contextmanager
def pty_pair(folder: Path) -> Iterator[tuple[str, str]]:
    board, host = folder / "ttyBOARD", folder / "ttyHOST"
    socat = subprocess.Popen(["socat", f"pty,raw,echo=0,link={board}",
                              f"pty,raw,echo=0,link={host}"])
    try:
        end = time.monotonic() + 10
        while not (board.exists() and host.exists()):
            if time.monotonic() > end:
                raise SystemExit("socat made no pty pair (apt-get install socat)")
            time.sleep(0.05)
        yield str(board), str(host)
    finally:
        socat.kill()
        socat.wait()


def skinhil(*args: str) -> list[str]:
    return [sys.executable, "-m", "skinhil", *args]


def quick_model(path: Path) -> None:
    """A classification model (listen needs one; the contact tasks do not use it)."""
    sys.path.insert(0, str(REPO))
    from skinhil.decoding.model_file import save_decoder
    from skinhil.receiver.training import train_decoder

    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False)
    save_decoder(decoder, path)


def run(task: str, who: str, folder: Path, model: Path, snr_db: float, seed: int,
        duration_s: float | None = None) -> dict:
    """The board's score of ``task`` answered by ``who``: the whole scenario, or its first
    ``duration_s`` s of board time."""
    scenario = REPO / "examples" / "scenarios" / f"task_{task}.toml"
    sys.path.insert(0, str(REPO))
    from skinhil.world.scenario_file import load_scenario

    if duration_s is None:
        duration_s = load_scenario(scenario).duration_s
    duration_s += 0.6  # the last answers' window
    score, truth = folder / f"{task}-{who}.json", folder / f"{task}-truth.jsonl"
    listen_args = ["--answer", "--answer-with", who, "--json"]
    if who == "oracle":
        listen_args += ["--oracle-truth", str(truth)]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    with pty_pair(folder) as (board_end, host_end):
        listen = subprocess.Popen(skinhil("listen", "--port", host_end, "--model", str(model),
                                          *listen_args), env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        time.sleep(6.0)  # listen is up before the run starts
        serve = subprocess.run(skinhil("serve", "--port", board_end, "--schedule",
                                       str(scenario), "--snr-db", str(snr_db), "--seed",
                                       str(seed), "--duration", f"{duration_s:.3f}",
                                       "--score", str(score), "--quiet",
                                       *(["--truth", str(truth)] if who == "reference" else [])),
                               env=env, capture_output=True, text=True, timeout=600)
        try:
            listen.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            listen.kill()
            listen.communicate()
    if serve.returncode:
        raise SystemExit(f"serve failed: {serve.stderr}")
    return json.loads(score.read_text())["tasks"].get(task, {})


def wilson(right: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval (95 %) of a proportion ``right`` / ``n``."""
    if n == 0:
        return 0.0, 1.0
    p = right / n
    mid = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(mid - half, 0.0), min(mid + half, 1.0)


def cell(s: dict, task: str) -> str:
    """One table cell: accuracy with its 95 % interval (right of matched + missed), late
    answers when any, slip's false alarms per minute, the task's error or latency."""
    if not s:
        return "n/a"
    key, unit = METRIC[task]
    value = s.get(key)
    if isinstance(value, dict):
        value = value.get("p50")
    scored = s["matched"] + s["misses"]
    lo, hi = wilson(s["right"], scored)
    acc_text = (f"{100 * s['right'] / scored:.0f} % [{100 * lo:.0f}-{100 * hi:.0f}]"
                if scored else "n/a")
    extra = (f", {s['false_alarms_per_min']:.1f} FA/min" if task == "slip"
             and s.get("false_alarms_per_min") is not None else "")
    late = f", {s['late']} late" if s.get("late") else ""
    metric = "" if value is None else f"; {key.replace('_', ' ')} {value:.3g} {unit}"
    return f"{acc_text} ({s['right']}/{scored}{late}{extra}){metric}"


def task_figures(s: dict, task: str, who: str) -> list[dict]:
    """One answerer's figures on one task: its accuracy and the task's error or latency."""
    if not s:
        return []
    key, unit = METRIC[task]
    scored = s["matched"] + s["misses"]
    out = [figure(f"{task}, {who}: right", round(100 * s["right"] / scored, 1) if scored
                  else "n/a", f"% of {scored} trials")]
    value = s.get(key)
    if isinstance(value, dict):
        value = value.get("p50")
    if value is not None:
        out.append(figure(f"{task}, {who}: {key.replace('_', ' ')}", float(f"{value:.3g}"),
                          unit))
    if task == "slip" and s.get("false_alarms_per_min") is not None:
        out.append(figure(f"{task}, {who}: false alarms", round(s["false_alarms_per_min"], 1),
                          "per min"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr-db", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=20,
                    help="the board's seed (the reference decoders are fitted on seeds 1-6)")
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--who", default=",".join(WHO),
                    help="answerers to run (the oracle needs the reference's truth file, "
                         "which the reference run of the same invocation writes)")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--smoke", action="store_true",
                    help=f"localisation only, the reference only, the scenario's first "
                         f"{SMOKE_DURATION_S:g} s (a check that the script runs)")
    add_arguments(ap)
    args = ap.parse_args()
    print(describe(), file=sys.stderr, flush=True)
    tasks = [t for t in args.tasks.split(",") if t]
    who = [w for w in args.who.split(",") if w]
    duration_s = None
    if args.smoke:
        tasks, who, duration_s = ["localisation"], ["reference"], SMOKE_DURATION_S
    results: dict[str, dict[str, dict]] = {}
    with tempfile.TemporaryDirectory(prefix="skinhil-tasks-") as tmp:
        folder = Path(tmp)
        model = folder / "model.npz"
        quick_model(model)
        for task in tasks:
            results[task] = {}
            for w in who:
                t0 = time.monotonic()
                results[task][w] = run(task, w, folder, model, args.snr_db, args.seed,
                                       duration_s)
                print(f"{task} {w}: {cell(results[task][w], task)} "
                      f"({time.monotonic() - t0:.0f} s)", file=sys.stderr, flush=True)
    print(f"| task (SNR {args.snr_db:g} dB) | " + " | ".join(who) + " |")
    print("|---|" + "---|" * len(who))
    for task in tasks:
        print(f"| {task} | " + " | ".join(cell(results[task][w], task) for w in who) + " |")
    if args.out is not None:
        args.out.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    publish(args, "tasks", f"Contact tasks at {args.snr_db:g} dB, board seed {args.seed}: "
            "reference, random and oracle answerers",
            [f for task in tasks for w in who for f in task_figures(results[task][w], task, w)])


if __name__ == "__main__":
    main()
