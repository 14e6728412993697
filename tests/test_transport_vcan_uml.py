"""Run every ``-m vcan`` test inside user-mode Linux when this host has no vcan0.

One UML boot per test module that uses the marker (boot costs about 2 s): a single pytest
process collecting them all grows past what UML can map on the host (see
``tests/uml_vcan.py``: ``vm.max_map_count``) and gets killed; one module per boot also says
which module failed. numba's cache is warmed on the host first, so nothing compiles inside.

These host-side tests fail (they do not skip) when UML is missing or any vcan test fails
there; they are skipped only where the vcan tests already run directly (the host has vcan0)
or when running inside UML.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
from conftest import HAS_VCAN
from uml_vcan import (
    UmlUnavailable,
    host_max_map_count,
    in_uml,
    run_in_uml,
    warm_numba_cache,
)

REPO = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
UML_TIMEOUT_S = 1200.0
"""Per module: the slowest, tests/test_receiver_online.py (100 stimuli at 10 dB and 27
noise-free through vcan0, a decoder trained inside UML), took 2.5-10 min on a 2-core
machine."""

VCAN_MODULES = sorted(p.name for p in HERE.glob("test_*.py")
                      if p.name != Path(__file__).name
                      and "mark.vcan" in p.read_text(encoding="utf-8"))

skip_here = pytest.mark.skipif(HAS_VCAN or in_uml(),
                               reason="vcan0 exists here: the vcan tests ran directly")


@pytest.fixture(scope="module")
def warm_cache() -> None:
    warm_numba_cache(REPO)


@skip_here
@pytest.mark.parametrize("module", VCAN_MODULES)
def test_vcan_tests_pass_inside_user_mode_linux(module: str, warm_cache: None) -> None:
    cmd = [sys.executable, "-m", "pytest", "-m", "vcan", "-q", "-s", "-rfEs", "-p",
           "no:cacheprovider", "--durations=3", str(HERE / module)]
    try:
        res = run_in_uml(cmd, REPO, timeout_s=UML_TIMEOUT_S)
    except UmlUnavailable as exc:
        pytest.fail(f"cannot run the vcan tests: {exc}")
    report = (f"{module}: boot {res.boot_s}, command {res.command_s}, total "
              f"{res.total_s:.1f} s\n--- output ---\n{res.output}\n--- console ---\n"
              f"{res.console[-3000:]}")
    print(report)
    if res.host_maps_exhausted:
        pytest.fail(f"{module}: a program inside UML was killed because the host's "
                    f"vm.max_map_count ({host_max_map_count()}) was reached; raise it with "
                    f"'sysctl -w vm.max_map_count=262144' or make the module lighter\n"
                    + report)
    assert res.returncode == 0, report
    passed = re.search(r"(\d+) passed", res.output)
    assert passed and int(passed.group(1)) >= 1, report
    assert "skipped" not in res.output.splitlines()[-1], report


def test_every_vcan_module_is_run() -> None:
    """The vcan modules found by the marker (guards against a rename hiding them)."""
    assert "test_transport_contract.py" in VCAN_MODULES
    assert "test_serve_can.py" in VCAN_MODULES
