"""The receiver side never needs the board emulator: nothing it imports pulls in firmware_sim.

Each check imports the modules in a fresh interpreter and looks at ``sys.modules``, so an
import hidden anywhere down the chain (a submodule, a re-export) is caught.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

_PROBE = """
import importlib, json, pkgutil, sys
names = []
for top in sys.argv[1:]:
    mod = importlib.import_module(top)
    names.append(top)
    for info in pkgutil.walk_packages(getattr(mod, "__path__", []), top + "."):
        importlib.import_module(info.name)
        names.append(info.name)
print(json.dumps({"imported": names,
                  "board": sorted(m for m in sys.modules if m.split(".")[0] == "firmware_sim")}))
"""


@pytest.mark.parametrize("package", ["skinhil.receiver", "skinhil.transports", "protocols",
                                     "skinhil.cli.listen", "skinhil.cli.demo",
                                     "skinhil.cli.train"])
def test_receiver_side_imports_nothing_from_firmware_sim(package: str) -> None:
    res = subprocess.run([sys.executable, "-c", _PROBE, package], capture_output=True,
                         text=True, timeout=120, check=False)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert package in out["imported"]
    assert out["board"] == [], f"{package} pulls in the board emulator: {out['board']}"


def test_probe_sees_the_board_when_it_is_imported() -> None:
    """The probe itself can fail: importing the board's CLI command does load firmware_sim."""
    res = subprocess.run([sys.executable, "-c", _PROBE, "skinhil.cli.serve"],
                         capture_output=True, text=True, timeout=120, check=False)
    assert res.returncode == 0, res.stderr
    assert "firmware_sim.board" in json.loads(res.stdout.strip().splitlines()[-1])["board"]
