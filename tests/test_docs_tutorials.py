"""The docs' quick shell commands run as written, so the tutorials cannot rot: every fenced
block marked ``{code-block} sh`` with ``:class: run-in-test`` in docs/ is run line by line
(``skinhil`` as ``python -m skinhil`` of this checkout) in a scratch folder that sees the
repository's ``examples/``, and every line must exit 0."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tests.harness.serve import REPO, serve_env

BLOCK = re.compile(r"```\{code-block\} sh\n:class: run-in-test\n(.*?)```", re.S)


def _commands() -> list[tuple[str, str]]:
    found = []
    for page in sorted((REPO / "docs").rglob("*.md")):
        for block in BLOCK.findall(page.read_text(encoding="utf-8")):
            for line in block.splitlines():
                line = line.split("  #", 1)[0].strip()
                if line:
                    found.append((str(page.relative_to(REPO)), line))
    return found


COMMANDS = _commands()


def test_the_docs_mark_commands_to_run() -> None:
    assert len(COMMANDS) >= 4
    assert {page for page, _ in COMMANDS} >= {"docs/tutorials/first-run.md"}


@pytest.mark.parametrize(("page", "line"), COMMANDS, ids=[c for _, c in COMMANDS])
def test_docs_command_runs(page: str, line: str, tmp_path: Path) -> None:
    (tmp_path / "examples").symlink_to(REPO / "examples")
    argv = shlex.split(line)
    assert argv[0] == "skinhil", f"{page}: a run-in-test line starts with skinhil: {line}"
    res = subprocess.run([sys.executable, "-m", "skinhil", *argv[1:]], cwd=tmp_path,
                         env=serve_env(), capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, f"{page}: {line}\n{res.stdout[-2000:]}\n{res.stderr[-2000:]}"
    assert res.stdout.strip() or any(tmp_path.iterdir()), f"{page}: {line} did nothing"
