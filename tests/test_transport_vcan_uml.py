"""Run every ``-m vcan`` test inside user-mode Linux when this host has no vcan0.

This host-side test fails (it does not skip) when UML is missing or any vcan test fails
there; it is skipped only where the vcan tests already run directly (the host has vcan0) or
when it is itself running inside UML.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
from conftest import HAS_VCAN
from uml_vcan import UmlUnavailable, in_uml, run_in_uml

REPO = Path(__file__).resolve().parents[1]
UML_TIMEOUT_S = 240.0


@pytest.mark.skipif(HAS_VCAN or in_uml(), reason="vcan0 exists here: the vcan tests ran "
                                                  "directly")
def test_vcan_tests_pass_inside_user_mode_linux() -> None:
    here = Path(__file__).resolve().parent
    # only the modules that use the marker: collecting every module inside UML is slow and
    # needs much more memory there
    me = Path(__file__).name
    files = sorted(str(p) for p in here.glob("test_*.py")
                   if p.name != me and "mark.vcan" in p.read_text(encoding="utf-8"))
    cmd = [sys.executable, "-m", "pytest", "-m", "vcan", "-q", "-rfEs", "-p",
           "no:cacheprovider", *files]
    try:
        res = run_in_uml(cmd, REPO, timeout_s=UML_TIMEOUT_S)
    except UmlUnavailable as exc:
        pytest.fail(f"cannot run the vcan tests: {exc}")
    report = (f"boot {res.boot_s}, command {res.command_s}, total {res.total_s:.1f} s\n"
              f"--- output ---\n{res.output}\n--- console ---\n{res.console[-3000:]}")
    print(report)
    assert res.returncode == 0, report
    passed = re.search(r"(\d+) passed", res.output)
    assert passed and int(passed.group(1)) >= 1, report
    assert "skipped" not in res.output.splitlines()[-1], report
