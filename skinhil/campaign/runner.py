"""A campaign played case by case, its summary and JUnit XML rewritten after each case.

Cases already in the summary of an earlier run (``resume``) are not played again. A stop
request (Ctrl-C) ends the case under way unrecorded (its processes ended), so the files on
disk always hold the cases played whole; ``complete`` says whether every case was.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from skinhil.campaign.campaign_file import Campaign
from skinhil.campaign.case_run import BenchLink, Stopped, run_case, slug
from skinhil.campaign.junit_report import write_junit
from skinhil.campaign.summary_file import load_summary, new_summary, totals, write_summary

SUMMARY_NAME = "summary.json"
JUNIT_NAME = "junit.xml"


def run_campaign(campaign: Campaign, out: Path, link: BenchLink, link_text: str,
                 stop: threading.Event, resume: bool = False,
                 on_case: Callable[[dict[str, Any] | None], None] | None = None
                 ) -> dict[str, Any]:
    """Play ``campaign``'s cases on ``link`` (described as ``link_text``), writing
    ``out/summary.json``, ``out/junit.xml`` and one folder per case under ``out/cases``;
    the summary. ``on_case(record)`` is called after each case played (``None`` for each
    case skipped as done)."""
    summary = load_summary(out / SUMMARY_NAME, campaign) if resume else \
        new_summary(campaign, link_text)
    out.mkdir(parents=True, exist_ok=True)
    cases = campaign.cases()
    done = {record["id"] for record in summary["cases"]}
    for index, case in enumerate(cases):
        if case.id in done:
            if on_case is not None:
                on_case(None)
            continue
        if stop.is_set():
            break
        folder = out / "cases" / f"{index + 1:04d}-{slug(case.id)}"
        try:
            record = run_case(case, folder, link, campaign.rig, stop)
        except Stopped:
            break
        summary["cases"].append(record)
        _save(summary, out, len(cases))
        if on_case is not None:
            on_case(record)
    _save(summary, out, len(cases))
    return summary


def _save(summary: dict[str, Any], out: Path, n_cases: int) -> None:
    summary["totals"] = totals(summary["cases"], n_cases)
    summary["complete"] = summary["totals"]["played"] == n_cases
    write_summary(out / SUMMARY_NAME, summary)
    write_junit(out / JUNIT_NAME, summary)
