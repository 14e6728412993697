"""Every compiled codec kernel stays inside its buffers: the wire codecs, the replay's
re-framing and the spike scan run in a bounds-checked build (``NUMBA_BOUNDSCHECK=1``, a fresh
kernel cache) over inputs longer than their buffers (``tests/harness/bounds_fuzz.py``). A
store out of bounds raises IndexError there; in the normal build it would corrupt memory."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_codec_kernels_write_nothing_out_of_bounds(tmp_path) -> None:
    env = dict(os.environ, NUMBA_BOUNDSCHECK="1", NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), str(TESTS.parent),
                                        env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, "-m", "harness.bounds_fuzz"], cwd=TESTS, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.startswith("ok ") and int(proc.stdout.split()[1]) > 300
