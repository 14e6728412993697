"""No compiled kernel runs stale code: numba's cache is keyed on all the package sources.

A fused kernel of ``skinhil.model.sensor`` (the linear mechanics' modal one) inlines
``skinhil.model.neurons._euler_step``.
numba alone keys the fused kernel's cache entry on ``sensor.py`` only, so after an edit of
``neurons.py`` it would load the old compiled code. Here a copy of the packages runs the
kernel in one process, the callee's constant is changed, and a new process must see the change.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from protocols.kernel_cache import KERNEL_PACKAGES, source_hash

REPO = Path(__file__).resolve().parent.parent

RUN_FUSED_KERNEL = """
import numpy as np
import numba
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
sensor = SkinSensor(SkinModel(SkinParams(mechanics="linear")), dt_s=1e-4)  # no noise
springs, spikes = sensor.advance(np.zeros((20, 77, 3)))  # the one-call compiled block
print(int(spikes.sum()), numba.config.CACHE_DIR)
"""


def _run(root: Path) -> tuple[int, Path]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(root)
    out = subprocess.run([sys.executable, "-c", RUN_FUSED_KERNEL], cwd=root, env=env,
                         check=True, capture_output=True, text=True, timeout=600)
    count, cache = out.stdout.split()
    return int(count), Path(cache)


def test_edit_of_an_inlined_callee_in_another_file_is_seen(tmp_path: Path) -> None:
    for name in KERNEL_PACKAGES:
        shutil.copytree(REPO / name, tmp_path / name,
                        ignore=shutil.ignore_patterns("__pycache__"))
    at_rest, cache_before = _run(tmp_path)
    assert at_rest == 0  # 2 ms at rest without noise: no spike
    assert cache_before.is_relative_to(tmp_path)
    assert any(cache_before.rglob("sensor._modal_sensor_kernel*.nbi"))  # cached on disk

    neurons = tmp_path / "skinhil" / "model" / "neurons.py"
    text = neurons.read_text()
    old = "return (vv + dt_ms * (0.04 * vv * vv + 5.0 * vv + 140.0 - uu + gain * current),"
    assert text.count(old) == 1
    neurons.write_text(text.replace(old, old.replace("140.0", "1.0e6")))  # fires every step
    assert source_hash(tmp_path) != cache_before.name

    driven, cache_after = _run(tmp_path)
    assert cache_after != cache_before
    assert driven > 0  # the fused kernel in sensor.py (unchanged) runs the new callee
