"""The campaign's JSON summary: one record per case played, rewritten whole (atomically)
after every case, so a run stopped at any point leaves a valid summary of what it did, and
``--resume`` reads it back to play only the cases it lacks.

Layout (``docs/campaigns.md``): ``format``, ``version``, ``campaign`` (name, file, SHA-256
of its text), ``link`` (where the cases played), ``complete`` (every case played),
``totals`` (cases, played, passed, failed, errors) and ``cases`` (each case's record:
:func:`skinhil.campaign.case_run.run_case`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from skinhil.campaign.campaign_file import Campaign
from skinhil.errors import ConfigError
from skinhil.output_files import write_text

FORMAT = "skinhil-campaign-summary"
VERSION = 1
OUTCOMES = ("passed", "failed", "error")


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
    """The summary at ``path`` of an earlier run of ``campaign``, or :class:`ConfigError`
    (none there, not a summary, or of another campaign or another version of its file)."""
    where = f"campaign summary '{path}'"
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"{where} not found — nothing to resume: run without --resume") \
            from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{where} cannot be read ({exc}) — run without --resume to start "
                          "anew") from None
    if not (isinstance(summary, dict) and summary.get("format") == FORMAT
            and summary.get("version") == VERSION and isinstance(summary.get("cases"), list)):
        raise ConfigError(f"{where} is not a skinhil campaign summary (version {VERSION}) — "
                          "give the --out folder of an earlier bench run")
    if summary["campaign"].get("sha256") != campaign.digest:
        raise ConfigError(f"{where} is of another campaign, or '{campaign.path}' changed "
                          "since — run without --resume to start anew")
    return summary
