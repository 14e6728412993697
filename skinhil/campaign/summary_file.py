"""The campaign's JSON summary: one record per case played, rewritten whole (atomically)
after every case, so a run stopped at any point leaves a valid summary of what it did, and
``--resume`` reads it back to play only the cases it lacks.

Layout (``docs/campaigns.md``): ``format``, ``version``, ``campaign`` (name, file, SHA-256
of its text), ``link`` (where the cases played), ``complete`` (every case played),
``totals`` (cases, played, passed, failed, errors) and ``cases`` (each case's record:
:func:`skinhil.campaign.case_run.run_case`); its JSON Schema is :mod:`skinhil.schemas`'
``campaign-summary``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from skinhil.campaign.campaign_file import Campaign
from skinhil.errors import ConfigError
from skinhil.model.schedule_file import read_schedule_text
from skinhil.output_files import write_text
from skinhil.schemas import validate

FORMAT = "skinhil-campaign-summary"
VERSION = 1
OUTCOMES = ("passed", "failed", "error")
MAX_SUMMARY_BYTES = 32 * 2**20
"""Largest summary ``--resume`` reads (32 MiB: a 10,000-case campaign's records with room for
long messages)."""


def new_summary(campaign: Campaign, link: str) -> dict[str, Any]:
    """An empty summary of ``campaign`` played on ``link`` (a description)."""
    return {"format": FORMAT, "version": VERSION,
            "campaign": {"name": campaign.name, "file": str(campaign.path),
                         "sha256": campaign.digest, "rig": campaign.rig.as_dict()},
            "link": link, "complete": False, "totals": totals([], len(campaign.cases())),
            "cases": []}


def totals(cases: list[dict[str, Any]], n_cases: int) -> dict[str, int]:
    """The counts of ``cases`` (records) out of ``n_cases``."""
    out = {"cases": n_cases, "played": len(cases)}
    for outcome in OUTCOMES:
        out["errors" if outcome == "error" else outcome] = sum(
            c["outcome"] == outcome for c in cases)
    return out


def write_summary(path: Path, summary: dict[str, Any]) -> None:
    """Write ``summary`` to ``path`` whole or not at all."""
    write_text(path, json.dumps(summary, indent=1) + "\n")


def load_summary(path: Path, campaign: Campaign) -> dict[str, Any]:
    """The summary at ``path`` of an earlier run of ``campaign``, read as untrusted input,
    or a one-line :class:`ConfigError`: none there; not a regular file that ends within the
    schedule reader's time bound; larger than :data:`MAX_SUMMARY_BYTES`; not JSON; not valid
    against the summary's schema (:mod:`skinhil.schemas` ``campaign-summary``: an unknown
    outcome, a missing or renamed key); of another campaign or another version of its file;
    a record of a case the campaign does not hold, or of one case twice."""
    where = f"campaign summary '{path}'"
    if not path.exists():
        raise ConfigError(f"{where} not found — nothing to resume: run without --resume")
    text, _ = read_schedule_text(path, "campaign summary", MAX_SUMMARY_BYTES,
                                 "give the summary.json that bench wrote, or run without "
                                 "--resume to start anew")
    try:
        summary = json.loads(text)
    except RecursionError:
        raise ConfigError(f"{where} nests too deeply to be a campaign summary — give the "
                          "summary.json that bench wrote, or run without --resume") from None
    except ValueError as exc:
        raise ConfigError(f"{where} is not JSON ({exc}) — run without --resume to start "
                          "anew") from None
    if not (isinstance(summary, dict) and summary.get("format") == FORMAT
            and summary.get("version") == VERSION):
        raise ConfigError(f"{where} is not a skinhil campaign summary (version {VERSION}) — "
                          "give the --out folder of an earlier bench run")
    validate("campaign-summary", summary, where)
    if summary["campaign"]["sha256"] != campaign.digest:
        raise ConfigError(f"{where} is of another campaign, or '{campaign.path}' changed "
                          "since — run without --resume to start anew")
    ids = [record["id"] for record in summary["cases"]]
    known = {case.id for case in campaign.cases()}
    strange = [i for i in ids if i not in known]
    if strange or len(set(ids)) != len(ids):
        what = f"a case the campaign does not hold ({strange[0]!r})" if strange \
            else "a case twice"
        raise ConfigError(f"{where} records {what} — give the summary that bench wrote for "
                          "this campaign, or run without --resume to start anew")
    return summary
