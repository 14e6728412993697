"""The wheel is the product: built by ``pip wheel`` and installed into a new venv, it holds
every file the code points at, its command line answers, the notebook API runs a board and a
receiver from outside the checkout and ``skinhil demo`` trains its decoder and plays; its
kernel cache falls back to the user's cache folder when the package folder cannot be
written, and says so."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from test_api import examples

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("skinhil", "firmware_sim", "protocols")

POINTED_AT = """
import importlib.util, json, sys, sysconfig
from pathlib import Path
import protocols, skinhil, firmware_sim
from importlib import resources
site = Path(sysconfig.get_paths()["purelib"]).resolve()
paths = [protocols.DBC_PATH, protocols.DBC_FD_PATH, protocols.SPEC_PATH,
         protocols.CONFORMANCE_PATH]
paths += [Path(p.__file__).with_name("py.typed") for p in (skinhil, firmware_sim, protocols)]
paths += [Path(str(resources.files("skinhil.view").joinpath("static", n)))
          for n in ("index.html", "view.js", "view.css")]
paths += [importlib.util.find_spec("skinhil.model.normals._kernel").origin]  # built by the wheel
print(json.dumps({"site": str(site), "paths": [str(Path(p).resolve()) for p in paths],
                  "missing": [str(p) for p in paths if not Path(p).is_file()],
                  "cases": len(json.loads(protocols.CONFORMANCE_PATH.read_text())["cases"])}))
"""


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A new venv (numpy etc. from this interpreter's site-packages) with the wheel built
    from a copy of the sources installed in it."""
    root = tmp_path_factory.mktemp("wheel")
    src = root / "src"
    for name in PACKAGES:
        shutil.copytree(REPO / name, src / name,
                        ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy2(REPO / name, src / name)
    dist = root / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps",
                    "--no-build-isolation", "-q", "-w", str(dist)], check=True,
                   capture_output=True, timeout=300)
    env_dir = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(env_dir)],
                   check=True, capture_output=True, timeout=300)
    wheel = next(dist.glob("skinhil-*.whl"))
    subprocess.run([str(env_dir / "bin" / "python"), "-m", "pip", "install", "--no-deps", "-q",
                    str(wheel)], check=True, capture_output=True, timeout=300)
    # the package folder's kernel cache cannot be made (as a read-only site-packages): a
    # file where its folder would be
    site = Path(subprocess.run([str(env_dir / "bin" / "python"), "-c",
                                "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    package_cache = site / "skinhil" / "__pycache__" / "numba"
    package_cache.parent.mkdir(parents=True, exist_ok=True)
    package_cache.write_text("not a folder: the package's kernel cache cannot be made\n")
    return env_dir


@pytest.fixture(scope="module")
def home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The user's folders of the tests that run the installed package: one kernel cache, so
    the kernels compile once for the module."""
    return tmp_path_factory.mktemp("home")


def _env(home: Path) -> dict[str, str]:
    """No PYTHONPATH, no kernel cache of this checkout: the installed package alone."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env["XDG_CACHE_HOME"] = str(home / "cache")
    return env


def test_every_file_the_code_points_at_is_in_site_packages(venv: Path, tmp_path: Path) -> None:
    import json

    out = subprocess.run([str(venv / "bin" / "python"), "-c", POINTED_AT], cwd=tmp_path,
                         env=_env(tmp_path), capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    info = json.loads(out.stdout)
    assert info["missing"] == []
    assert all(Path(p).is_relative_to(venv.resolve()) for p in info["paths"]), info
    assert info["cases"] > 0


def test_the_command_line_answers(venv: Path, tmp_path: Path) -> None:
    skinhil = str(venv / "bin" / "skinhil")
    version = subprocess.run([skinhil, "--version"], cwd=tmp_path, env=_env(tmp_path),
                             capture_output=True, text=True, timeout=300)
    assert version.returncode == 0, version.stderr
    assert version.stdout.startswith("skinhil 0.1.0 (wire protocol versions 3, 4)")
    out = tmp_path / "board.dbc"
    dbc = subprocess.run([skinhil, "dbc", "--out", str(out)], cwd=tmp_path, env=_env(tmp_path),
                         capture_output=True, text=True, timeout=300)
    assert dbc.returncode == 0, dbc.stderr
    assert out.read_text() == (REPO / "protocols" / "skinhil.dbc").read_text()


def test_the_api_runs_and_the_kernel_cache_falls_back_to_the_users(venv: Path, home: Path,
                                                                   tmp_path: Path) -> None:
    code = "import logging; logging.basicConfig(level=logging.INFO)\n" + examples()[0]
    run = subprocess.run([str(venv / "bin" / "python"), "-c", code], cwd=tmp_path,
                         env=_env(home), capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    received, sent = map(int, run.stdout.split())
    assert 0 < received <= sent
    user_cache = home / "cache" / "skinhil" / "numba"
    assert f"kernel cache: {user_cache}" in run.stderr
    assert any(user_cache.rglob("*.nbi"))  # compiled and cached there


def test_the_demo_trains_its_decoder_and_plays(venv: Path, home: Path, tmp_path: Path) -> None:
    """``skinhil demo`` as a new user runs it: no decoder cached, so it trains one from the
    package's own files, caches it in the user's folder and plays the board against it."""
    demo = subprocess.run([str(venv / "bin" / "skinhil"), "demo", "--duration", "1", "--quiet"],
                          cwd=tmp_path, env=_env(home), capture_output=True, text=True,
                          timeout=900)
    assert demo.returncode == 0, demo.stderr[-3000:]
    assert "accuracy" in demo.stdout and "right / scored stimuli" in demo.stdout, demo.stdout
    assert any((home / "cache" / "skinhil").glob("demo-decoder-*.npz"))
