"""The report card of a suite run (``skinhil bench --suite``): per task the decoder's
headline score pooled over the seeds with its 95 % interval (:mod:`.interval`), the
baselines' at the same seeds beside it, the suite and its version, skinhil's and the
wire's versions, and the seeds drawn; as JSON (``report-card.json``, its schema
``skinhil/schemas/report-card.schema.json``) and Markdown (``report-card.md``).

The numbers come from the board's score files only (each case's ``score.json``): a task's
``charged`` (the denominator of its headline ``score`` under the task's rule: trials +
answers - matched, or for a detection task the trials; :func:`counts`) and ``right`` (the
score times charged), the grasp's lifts won and lifts; the pooled score is the sum of
``right`` over the sum of ``charged``, so a seed's hedged or cancelled answers stay charged.
A case whose board wrote no score file (the rig's error) adds nothing and is listed with its
reason; a baseline that answered a task at no seed has no score for it (it does not play it).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from protocols.constants import KNOWN_VERSIONS
from skinhil import __version__
from skinhil.campaign.interval import METHOD, wilson_interval
from skinhil.campaign.suite_run import BASELINES, SuiteRun
from skinhil.output_files import write_text
from skinhil.suites import Suite
from skinhil.tasks.registry import by_name

FORMAT = "skinhil-report-card"
VERSION = 1
CARD_JSON = "report-card.json"
CARD_MD = "report-card.md"
CLASSIFICATION = "classification"
"""The task DECISIONs answer: scored by the board's DECISION scoreboard."""
GRASP = "grasp"
"""The card's key of the held object's score (the score file's ``grasp``)."""


def _score_file(record: Mapping[str, Any]) -> dict[str, Any] | None:
    try:
        data = json.loads((Path(record["folder"]) / "score.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _section(score: Mapping[str, Any], task: str) -> Mapping[str, Any] | None:
    # the part of a score file that scores ``task``: the DECISION scoreboard's top level for
    # CLASSIFICATION, ``grasp`` for GRASP, else ``tasks.<task>``; None if the file has none
    if task == CLASSIFICATION and task not in (score.get("tasks") or {}):
        return score if "onsets" in score else None
    part = score.get("grasp") if task == GRASP else (score.get("tasks") or {}).get(task)
    return part if isinstance(part, Mapping) else None


def counts(score: Mapping[str, Any], task: str) -> tuple[int, int] | None:
    """(right, charged) of ``task`` (or :data:`GRASP`) in a score file, so that right /
    charged is the file's own headline ``score`` under the task's rule (SPEC.md §3.5.4):
    charged is the trials and every answer that answered no trial first, or for a detection
    task (SLIP) the trials alone, and right the score times charged (a hedged right answer
    and a detection cancelled by an unmatched answer count for nothing); for :data:`GRASP`
    the lifts. None if the file has none. :data:`CLASSIFICATION` is the DECISION
    scoreboard's, at the score file's top level."""
    s = _section(score, task)
    if s is None:
        return None
    if task == GRASP:
        charged = int(s.get("lifts") or 0)
        if not charged:
            return None
    elif task == CLASSIFICATION and s is score:
        charged = int(s["onsets"]) + int(s["decisions"]) - int(s["matched"])
    elif by_name(task).detection:
        charged = int(s["trials"])
    else:
        charged = int(s["trials"]) + int(s["answers"]) - int(s["matched"])
    return round(float(s.get("score") or 0.0) * charged), charged


def case_tasks(suite: Suite) -> dict[str, list[str]]:
    """Each case's scored keys: the tasks it poses, and :data:`GRASP` if it holds an
    object."""
    return {c.name: [t.name for t in c.tasks] + ([GRASP] if c.held_object else [])
            for c in suite.cases}


def pooled(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Rows of ``right`` and ``charged`` (one per seed) pooled: ``score`` the sum of right
    over the sum of charged (None if nothing was charged), its 95 % Wilson ``interval``,
    ``right``, ``charged``."""
    k = sum(r["right"] for r in rows)
    n = sum(r["charged"] for r in rows)
    ci = wilson_interval(k, n)
    return {"score": k / n if n else None, "interval": None if ci is None else list(ci),
            "right": k, "charged": n}


def _rows(summary: Mapping[str, Any], case: str, task: str) -> list[dict[str, Any]]:
    rows = []
    for record in summary["cases"]:
        if record["scenario"] != case:
            continue
        score = _score_file(record)
        c = None if score is None else counts(score, task)
        if c is None:
            continue
        rows.append({"seed": record["seed"], "score": c[0] / c[1] if c[1] else None,
                     "right": c[0],
                     "charged": c[1], "outcome": record["outcome"]})
    return rows


def answers_sent(score: Mapping[str, Any], task: str) -> int:
    """How many answers to ``task`` a score file counts (DECISIONs for
    :data:`CLASSIFICATION`, GRIPs accepted for :data:`GRASP`)."""
    s = _section(score, task) or {}
    if task == GRASP:
        return int((s.get("grips") or {}).get("accepted") or 0)
    return int(s.get("decisions" if s is score else "answers") or 0)


def _baseline(summary: Mapping[str, Any], case: str, task: str) -> dict[str, Any]:
    """A baseline's pooled entry; its score and interval null where it answered ``task`` at
    no seed (an answerer that does not play that task is no baseline of it)."""
    entry = pooled(_rows(summary, case, task))
    files = [_score_file(r) for r in summary["cases"] if r["scenario"] == case]
    if not any(answers_sent(s, task) for s in files if s is not None):
        entry.update(score=None, interval=None)
    return entry


def build_card(suite: Suite, run: SuiteRun, draw_seed: int, seeds: list[int],
               link: str) -> dict[str, Any]:
    """The card's JSON-ready data (module docstring)."""
    played = {r["scenario"] for r in run.decoder["cases"]}
    tasks: dict[str, Any] = {}
    grasp: dict[str, Any] | None = None
    for case, keys in case_tasks(suite).items():
        if case not in played:
            continue
        for key in keys:
            rows = _rows(run.decoder, case, key)
            entry = {"case": case, **pooled(rows), "seeds": rows,
                     "baselines": {name: _baseline(s, case, key)
                                   for name, s in run.baselines.items()}}
            if key == GRASP:
                grasp = entry
            else:
                tasks[key] = entry
    ev = suite.evaluation_seeds
    card: dict[str, Any] = {
        "format": FORMAT, "version": VERSION,
        "suite": {"id": suite.id, "name": suite.name, "version": suite.version},
        "versions": {"skinhil": __version__, "wire": sorted(KNOWN_VERSIONS)},
        "draw": {"seed": draw_seed, "seeds": seeds, "evaluation_seeds": [ev.start, ev.stop - 1]},
        "interval": {"method": METHOD, "level": 0.95,
                     "of": "right over charged, pooled over the seeds"},
        "link": link, "complete": bool(run.decoder["complete"]) and all(
            s["complete"] for s in run.baselines.values()),
        "baselines": [n for n in BASELINES if n in run.baselines],
        "tasks": tasks,
        "cases": [{"id": r["id"], "case": r["scenario"], "seed": r["seed"],
                   "outcome": r["outcome"], "message": r["message"],
                   "folder": r["folder"]} for r in run.decoder["cases"]],
        "totals": run.decoder["totals"],
    }
    if grasp is not None:
        card["grasp"] = grasp
    return card


def cell(entry: Mapping[str, Any] | None) -> str:
    """A card entry as ``score [lo, hi] (right/charged)``, or ``n/a`` where it has no score."""
    if entry is None or entry["score"] is None:
        return "n/a"
    lo, hi = entry["interval"]
    return f"{entry['score']:.2f} [{lo:.2f}, {hi:.2f}] ({entry['right']}/{entry['charged']})"


def card_markdown(card: Mapping[str, Any]) -> str:
    """The card as Markdown: its versions, the seeds, one row per task, the cases that did
    not pass."""
    names = card["baselines"]
    lines = [f"# Report card: {card['suite']['id']}", "",
             f"- suite {card['suite']['id']} (version {card['suite']['version']}), skinhil "
             f"{card['versions']['skinhil']}, wire version(s) "
             f"{', '.join(map(str, card['versions']['wire']))}",
             f"- link: {card['link']}",
             f"- seeds per case: {', '.join(map(str, card['draw']['seeds']))} (drawn with "
             f"--seed {card['draw']['seed']}; the same --seed draws them again)",
             f"- score: right / charged, pooled over the seeds; [95 % {card['interval']['method']}"
             " interval] (right/charged)", ""]
    head = ["task", "case", "decoder", *names]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    rows = [(k, v) for k, v in card["tasks"].items()]
    if "grasp" in card:
        rows.append(("grasp", card["grasp"]))
    for key, e in rows:
        cells = [key, e["case"], cell(e), *(cell(e["baselines"][n]) if n in e["baselines"]
                                            else "n/a" for n in names)]
        lines.append("| " + " | ".join(cells) + " |")
    t = card["totals"]
    lines += ["", f"Cases: {t['played']} of {t['cases']} played, {t['passed']} passed, "
                  f"{t['failed']} failed (decoder), {t['errors']} errors (rig)."]
    bad = [c for c in card["cases"] if c["outcome"] != "passed"]
    if bad:
        lines += ["", "| case | seed | outcome | why |", "|---|---|---|---|"]
        lines += [f"| {c['case']} | {c['seed']} | {c['outcome']} | {c['message']} |"
                  for c in bad]
    return "\n".join(lines) + "\n"


def write_card(out: Path, card: Mapping[str, Any]) -> tuple[Path, Path]:
    """Write ``card`` as ``out/report-card.json`` and ``out/report-card.md``; their paths."""
    js, md = out / CARD_JSON, out / CARD_MD
    write_text(js, json.dumps(card, indent=1) + "\n")
    write_text(md, card_markdown(card))
    return js, md
