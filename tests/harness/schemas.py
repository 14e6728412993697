"""Outputs of real runs checked against skinhil's JSON Schemas (:mod:`skinhil.schemas`):
a score file, truth lines, a process's ready and summary lines, a bench folder."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from skinhil.process_output import READY, SUMMARY, records
from skinhil.schemas import validate


def check_file(name: str, path: Path) -> Any:
    """The JSON document at ``path``, valid against schema ``name``."""
    document = json.loads(path.read_text(encoding="utf-8"))
    validate(name, document, str(path))
    return document


def check_lines(name: str, path: Path) -> list[Any]:
    """The JSON lines at ``path``, each valid against schema ``name``."""
    rows = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]
    for i, row in enumerate(rows):
        validate(name, row, f"{path}:{i + 1}")
    return rows


def check_process_lines(lines: list[dict[str, Any]], where: str) -> None:
    """The ready line of ``lines`` (a process's JSON lines) and its summary line (of
    ``listen``: on one board), valid against their schemas; at least the ready line is
    there."""
    ready = [r for r in lines if r.get("type") == READY]
    assert ready, f"{where}: no ready line"
    for r in ready:
        validate("ready-line", r, where)
    for r in lines:
        if r.get("type") == SUMMARY and "boards" not in r:  # one board
            validate(f"{ready[0]['command']}-summary-line", r, where)


def check_bench_out(out: Path) -> None:
    """A bench ``--out`` folder: its summary and, for each case played, the board's score
    file and the board's and the reference receiver's process lines."""
    summary = check_file("campaign-summary", out / "summary.json")
    for record in summary["cases"]:
        folder = Path(record["folder"])
        if (folder / "score.json").exists():
            check_file("score", folder / "score.json")
        for name in ("board.out", "decoder.out"):
            if (folder / name).exists() and (folder / name).stat().st_size:
                check_process_lines(records((folder / name).read_text()), str(folder / name))
