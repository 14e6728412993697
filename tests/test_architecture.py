"""The layout is a contract: import-linter's contracts hold (and can fail), no two files import
each other round a circle, and the public API and the README's examples keep working."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import grimp
import pytest

import skinhil

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("skinhil", "firmware_sim", "protocols")
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def _lint_imports(root: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(root)}
    return subprocess.run([str(LINT_IMPORTS), "--no-cache"], cwd=root, env=env,
                          capture_output=True, text=True, timeout=300, check=False)


def test_import_contracts_hold() -> None:
    res = _lint_imports(REPO)
    assert res.returncode == 0, res.stdout + res.stderr
    assert " broken" not in res.stdout.lower().replace("0 broken", "")


def test_import_contracts_catch_a_forbidden_import(tmp_path: Path) -> None:
    """A copy of the packages where the model imports the board fails the contracts."""
    for name in PACKAGES:
        shutil.copytree(REPO / name, tmp_path / name,
                        ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(REPO / "pyproject.toml", tmp_path / "pyproject.toml")
    geometry = tmp_path / "skinhil" / "model" / "geometry.py"
    geometry.write_text(geometry.read_text() + "\nimport firmware_sim.board  # noqa\n")
    res = _lint_imports(tmp_path)
    assert res.returncode != 0
    assert "skinhil.model.geometry -> firmware_sim.board" in res.stdout


def _cycles(graph: grimp.ImportGraph) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    found: list[list[str]] = []
    for root in sorted(graph.modules):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.find_modules_directly_imported_by(root))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(
                        graph.find_modules_directly_imported_by(child)))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_no_import_cycle_between_files() -> None:
    graph = grimp.build_graph(*PACKAGES, cache_dir=None)
    assert _cycles(graph) == []


def test_cycle_finder_sees_a_cycle() -> None:
    graph = grimp.ImportGraph()
    for name in ("a", "a.x", "a.y", "a.z"):
        graph.add_module(name)
    graph.add_import(importer="a.x", imported="a.y")
    graph.add_import(importer="a.y", imported="a.x")
    graph.add_import(importer="a.y", imported="a.z")
    assert _cycles(graph) == [["a.x", "a.y"]]


@pytest.mark.parametrize("name", skinhil.__all__)
def test_every_public_name_imports(name: str) -> None:
    namespace: dict[str, object] = {}
    exec(f"from skinhil import {name}", namespace)  # noqa: S102  (the user's own line)
    assert namespace[name] is getattr(skinhil, name)


def test_readme_python_examples_run() -> None:
    blocks = re.findall(r"```python\n(.*?)```", (REPO / "README.md").read_text(), re.S)
    assert blocks
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})  # noqa: S102


LINK_KIND_TEST = re.compile(r'kind ?[!=]= ?"(can|serial|udp)"|is_can|getattr\([^)]*"fd"')
"""A string test of a link's kind or a probe of its FD flag: what differs by link is a
property of the link object (skinhil/transports), asked, never tested by name."""


def _link_kind_tests(roots: list[Path], allowed: Path) -> list[str]:
    found = []
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            if path.is_relative_to(allowed):
                continue
            for n, line in enumerate(path.read_text().splitlines(), 1):
                if LINK_KIND_TEST.search(line):
                    found.append(f"{path.relative_to(root.parent)}:{n}: {line.strip()}")
    return found


def test_no_link_kind_test_outside_the_links() -> None:
    found = _link_kind_tests([REPO / "skinhil", REPO / "firmware_sim"],
                             REPO / "skinhil" / "transports")
    assert not found, "ask the link's properties instead:\n" + "\n".join(found)


def test_link_kind_check_sees_a_kind_test(tmp_path: Path) -> None:
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "m.py").write_text('if transport.kind == "can":\n    pass\n')
    assert len(_link_kind_tests([pkg], tmp_path / "links")) == 1


BOARD_MAX_LINES = 300
"""The board keeps the clock and the list of participants; a job of its own is a participant
(firmware_sim/*_stage.py), not more lines here."""


def test_the_board_keeps_only_the_clock_and_its_participants() -> None:
    lines = len((REPO / "firmware_sim" / "board.py").read_text().splitlines())
    assert lines <= BOARD_MAX_LINES, (
        f"firmware_sim/board.py has {lines} lines: move a job into a participant")
