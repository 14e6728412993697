"""No figure tied to a machine or a load in the packages' docstrings and comments: such
figures live in ``benchmarks/results/`` (the docs' Benchmarks page). The packages are
skinhil/, firmware_sim/ and protocols/, their Python sources and the text files they ship."""

from __future__ import annotations

import re

from tests.harness.serve import REPO

MACHINE_OR_LOAD = re.compile(
    r"load average|\bat load\b|\bload [0-9~]|\bZen ?[0-9]|Xeon|EPYC|on this VM|(?-i:\bVM\b)|"
    r"[0-9.]+ ?GHz|\b20[0-9]{2}-[01][0-9]-[0-3][0-9]\b", re.I)


def test_no_machine_or_load_figures_in_the_packages() -> None:
    hits = []
    for package in ("skinhil", "firmware_sim", "protocols"):
        for path in sorted((REPO / package).rglob("*")):
            if path.suffix not in (".py", ".md", ".txt") or "__pycache__" in path.parts:
                continue
            for no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if MACHINE_OR_LOAD.search(line):
                    hits.append(f"{path.relative_to(REPO)}:{no}: {line.strip()}")
    assert not hits, "\n".join(hits)
