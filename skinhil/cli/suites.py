"""``skinhil suites``: the suites shipped, their versions, cases, the tasks each case poses
and the seed ranges (docs: Suites)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from skinhil.cli.conventions import add_json_option
from skinhil.suites import SUITES, Suite


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "suites", help="list the task suites, their cases and versions",
        description="List every suite shipped (name-vVERSION), its cases with the tasks each "
                    "poses (tolerances, classes) and its trial count, and the seeds for "
                    "training and for evaluation. Play a case with "
                    "'skinhil serve --suite SUITE:CASE --seed N'.")
    add_json_option(p)


def suite_data(s: Suite) -> dict[str, Any]:
    """A suite as JSON-ready data."""
    return {"suite": s.id, "name": s.name, "version": s.version, "about": s.about,
            "training_seeds": [s.training_seeds.start, s.training_seeds.stop - 1],
            "evaluation_seeds": [s.evaluation_seeds.start, s.evaluation_seeds.stop - 1],
            "cases": [{"case": c.name, "about": c.about, "trials": c.trials,
                       "held_object": c.held_object,
                       "tasks": [{"task": t.name, "tolerance": t.tolerance, "unit": t.unit,
                                  "classes": list(t.classes)} for t in c.tasks]}
                      for c in s.cases]}


def _task_text(t: dict[str, Any]) -> str:
    text = t["task"]
    if t["tolerance"] is not None:
        text += f" (±{t['tolerance']:g} {t['unit']})"
    if t["classes"]:
        unit = f" {t['unit']}" if t["unit"] else ""
        text += f" (classes {', '.join(f'{c:g}' for c in t['classes'])}{unit})"
    return text


def run(args: argparse.Namespace) -> int:
    data = [suite_data(s) for s in SUITES.values()]
    if args.json:
        print(json.dumps({"suites": data}))
        return 0
    for s in data:
        tr, ev = s["training_seeds"], s["evaluation_seeds"]
        print(f"{s['suite']}: {s['about']}; training seeds {tr[0]}-{tr[1]}, evaluation seeds "
              f"{ev[0]}-{ev[1]}")
        for c in s["cases"]:
            poses = ", ".join(_task_text(t) for t in c["tasks"])
            if c["held_object"]:
                poses = ", ".join(p for p in (poses, "grasp (held object)") if p)
            print(f"  {s['suite']}:{c['case']}  {c['trials']} trials; poses {poses}; "
                  f"{c['about']}")
    return 0
