"""The README is short and timeless: at most 200 lines and 12 kB, no measurement log (load
averages, machine names, before/after figures), the test command CI runs kept as it is, and
every file it links to present."""

from __future__ import annotations

import re

from tests.harness.serve import REPO

README = (REPO / "README.md").read_text(encoding="utf-8")

MEASUREMENT_LOG = re.compile(
    r"load average|\bload [0-9~]|(?-i:\bVM\b)|\bZen\b|Xeon|EPYC|GHz|\bbefore\b.*→|"
    r"\b20[0-9]{2}-[01][0-9]-[0-3][0-9]\b|wall time|measured on", re.I)


def test_readme_is_short() -> None:
    assert len(README.splitlines()) <= 200
    assert len(README.encode("utf-8")) <= 12 * 1024


def test_readme_has_no_measurement_log() -> None:
    hits = [line for line in README.splitlines() if MEASUREMENT_LOG.search(line)]
    assert not hits, hits


def test_readme_keeps_the_test_command_ci_runs() -> None:
    assert '\npip install -e ".[test]" && python -m pytest\n' in README


def test_readme_links_point_at_files_that_exist() -> None:
    links = re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", README)
    assert links
    missing = [link for link in links if not (REPO / link).exists()]
    assert not missing, missing
