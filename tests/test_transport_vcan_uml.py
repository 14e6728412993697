"""Run every ``-m vcan`` test inside user-mode Linux when this host has no vcan0.

One UML boot per test module that uses the marker (boot costs about 2 s): a single pytest
process collecting them all grows past what UML can map on the host (see
``tests/uml_vcan.py``: ``vm.max_map_count``) and gets killed; one module per boot also says
which module failed. numba's cache is warmed on the host first, so nothing compiles inside.
A UML machine has one CPU and runs on one host core while this pytest waits, so the modules
run :data:`AT_ONCE` machines at a time (the slowest first), from the first of these tests on.

These host-side tests fail (they do not skip) when UML is missing or any vcan test fails
there; they are skipped only where the vcan tests already run directly (the host has vcan0)
or when running inside UML.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import pytest
from conftest import HAS_VCAN
from uml_vcan import (
    UmlResult,
    UmlUnavailable,
    host_max_map_count,
    in_uml,
    run_in_uml,
    warm_numba_cache,
)

REPO = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
UML_TIMEOUT_S = 1200.0
"""Per module: the slowest, tests/test_receiver_online.py (50 stimuli at 10 dB, 27 noise-free
and 10 with dropped frames through vcan0, two decoders trained inside UML), took 1.5-3 min on
a 2-core machine."""

VCAN_MODULES = sorted(p.name for p in HERE.glob("test_*.py")
                      if p.name != Path(__file__).name
                      and "mark.vcan" in p.read_text(encoding="utf-8"))

skip_here = pytest.mark.skipif(HAS_VCAN or in_uml(),
                               reason="vcan0 exists here: the vcan tests ran directly")


AT_ONCE = 2
"""UML machines running at once: the 2-core CI machine runs the seven modules in about half
the time of one after the other."""
SLOWEST_FIRST = ("test_receiver_online.py", "test_answer_loop.py", "test_record_replay.py")
"""Started first, so the others fill the second machine meanwhile."""


def _run_module(module: str) -> UmlResult:
    cmd = [sys.executable, "-m", "pytest", "-m", "vcan", "-q", "-s", "-rfEs", "-p",
           "no:cacheprovider", "--durations=3", str(HERE / module)]
    return run_in_uml(cmd, REPO, timeout_s=UML_TIMEOUT_S)


@pytest.fixture(scope="module")
def uml_runs() -> Iterator[dict[str, Future[UmlResult]]]:
    """Every vcan module's UML run, started :data:`AT_ONCE` at a time (the cache warmed first)."""
    warm_numba_cache(REPO)
    order = [m for m in SLOWEST_FIRST if m in VCAN_MODULES] + [
        m for m in VCAN_MODULES if m not in SLOWEST_FIRST]
    with ThreadPoolExecutor(max_workers=AT_ONCE) as pool:
        yield {m: pool.submit(_run_module, m) for m in order}


@skip_here
@pytest.mark.parametrize("module", VCAN_MODULES)
def test_vcan_tests_pass_inside_user_mode_linux(
        module: str, uml_runs: dict[str, Future[UmlResult]]) -> None:
    try:
        res = uml_runs[module].result()
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
