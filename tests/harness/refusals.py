"""Bad command lines run in this process: each must be refused with one ``skinhil: error:``
line naming what was wrong, and exit status 2."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Protocol


class Refusal(Protocol):
    """A bad command line: its ``name``, its ``argv`` and a ``word`` the error line holds."""

    name: str
    argv: Any
    word: str


def refusal_failures(cases: Iterable[Refusal], capsys: Any) -> list[str]:
    """Run each case through ``skinhil.cli.main``; one line per case not refused as it must
    be (status, the tail of stderr)."""
    from skinhil.cli import main

    failures = []
    for case in cases:
        capsys.readouterr()
        try:
            status = main(list(case.argv))
        except SystemExit as exc:  # argparse's refusals exit
            status = exc.code
        err = capsys.readouterr().err
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if not (status == 2 and len(lines) == 1 and lines[0].startswith("skinhil: error: ")
                and case.word.lower() in lines[0].lower()):
            failures.append(f"{case.name}: status {status}, stderr {err[-500:]!r}")
    return failures
