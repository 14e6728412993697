"""The normals kernel (skinhil/model/normals/): its three paths agree bit for bit, its draws
are standard normal, and a path is forced by the environment.

Each path runs in a process of its own (``SKINHIL_NORMALS_PATH`` is read at import) and hashes
the normals of 10^6 (key, step) pairs; the Gaussian checks run on the path in use here.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from skinhil import NeuronPopulation
from skinhil.model.normals import PATH_ENV, fill_normals, normals_path, supported_paths
from skinhil.model.rng import TAIL_BOUND, seed_keys

REPO = Path(__file__).resolve().parent.parent

HASH_NORMALS = """
import hashlib, numpy as np
from skinhil.model.normals import fill_normals, normals_path
from skinhil.model.rng import seed_keys
keys = seed_keys(46, 1003)  # 62 blocks of 16 and a remainder of 11: every path's tail loop
z1, z2 = np.empty(1003, np.float32), np.empty(1003, np.float32)
h = hashlib.sha256()
for step in range(0, 997 * 7919, 7919):  # 997 steps spread over the counter
    fill_normals(keys, step, z1, z2)
    h.update(z1.tobytes()); h.update(z2.tobytes())
print(normals_path(), h.hexdigest())
"""


def _env(path: str | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != PATH_ENV}
    if path is not None:
        env[PATH_ENV] = path
    others = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), *others])
    return env


def _run(code: str, path: str | None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], env=_env(path), cwd=REPO.parent,
                          capture_output=True, text=True, timeout=600)


def _normals(n_keys: int, n_steps: int, seed: int) -> np.ndarray:
    """The 2·n_keys·n_steps normals of ``n_keys`` keys of ``seed`` at steps 0.. n_steps-1."""
    keys = seed_keys(seed, n_keys)
    out = np.empty((n_steps, 2, n_keys), np.float32)
    for step in range(n_steps):
        fill_normals(keys, step, out[step, 0], out[step, 1])
    return out.ravel()


@pytest.fixture(scope="module")
def draws() -> np.ndarray:
    """10^7 normals (float64 for the statistics)."""
    return _normals(5000, 1000, seed=2026).astype(np.float64)


def test_every_path_gives_the_same_normals_bit_for_bit() -> None:
    paths = supported_paths()
    assert "portable" in paths
    digests = {}
    for path in paths:
        out = _run(HASH_NORMALS, path)
        assert out.returncode == 0, out.stderr
        used, digest = out.stdout.split()
        assert used == path
        digests[path] = digest
    assert len(set(digests.values())) == 1, digests


def test_a_path_the_kernel_does_not_have_is_refused_in_one_line() -> None:
    out = _run("import skinhil.model.normals", "sse9")
    assert out.returncode != 0
    assert f"{PATH_ENV}='sse9' is not a path of the normals kernel" in out.stderr


def test_the_widest_path_the_cpu_runs_is_chosen() -> None:
    out = _run("from skinhil.model.normals import normals_path; print(normals_path())", None)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == supported_paths()[-1]


def test_a_draw_is_a_function_of_key_and_step_alone() -> None:
    keys = seed_keys(7, 40)
    z1, z2 = np.empty(40, np.float32), np.empty(40, np.float32)
    fill_normals(keys, 123, z1, z2)
    for i in (0, 17, 39):  # one channel alone, a block of one: the same pair
        a, b = np.empty(1, np.float32), np.empty(1, np.float32)
        fill_normals(keys[i:i + 1].copy(), 123, a, b)
        assert (a[0], b[0]) == (z1[i], z2[i])
    y1, y2 = np.empty(40, np.float32), np.empty(40, np.float32)
    fill_normals(keys, 124, y1, y2)
    assert not np.any(y1 == z1)  # another step: other draws


def test_moments_to_the_fourth(draws: np.ndarray) -> None:
    n = draws.size
    # standard errors of the sample moments of a normal: sqrt(Var(X^k) / n)
    for k, exact, var in ((1, 0.0, 1.0), (2, 1.0, 2.0), (3, 0.0, 15.0), (4, 3.0, 96.0)):
        m = float(np.mean(draws**k))
        assert abs(m - exact) < 5 * math.sqrt(var / n), (k, m)


def test_kolmogorov_smirnov_and_chi_square(draws: np.ndarray) -> None:
    assert stats.kstest(draws, "norm").pvalue > 1e-4
    edges = stats.norm.ppf(np.linspace(0, 1, 201))  # 200 equiprobable bins
    counts = np.histogram(draws, bins=np.r_[-np.inf, edges[1:-1], np.inf])[0]
    assert stats.chisquare(counts).pvalue > 1e-4


def test_tails_from_three_to_five_sigma_and_the_bound(draws: np.ndarray) -> None:
    more = _normals(5000, 3000, seed=2027).astype(np.float64)
    z = np.abs(np.concatenate([draws, more]))
    n = z.size
    for t in (3.0, 3.5, 4.0, 4.5, 5.0):
        p = 2 * stats.norm.sf(t)
        lo, hi = stats.binom.interval(1 - 1e-6, n, p)
        assert lo <= np.count_nonzero(z > t) <= hi, t
    assert z.max() <= TAIL_BOUND


def test_the_tail_bound_is_the_radius_of_the_smallest_uniform() -> None:
    u = np.float32(0.5) * np.float32(2.0**-32)  # word half 0: u = (0 + 1/2) 2^-32
    assert TAIL_BOUND == pytest.approx(math.sqrt(-2 * math.log(float(u))), rel=1e-12)
    assert 6.76 < TAIL_BOUND < 6.77


def test_the_path_in_use_is_one_the_cpu_runs() -> None:
    assert normals_path() in supported_paths()


BOARD_SPIKES = """
import hashlib, sys
sys.path.insert(0, {tests!r})
import protocols
from firmware_sim.board import Board, BoardConfig
from harness.golden import GoldenLink, capture_bytes
from skinhil.model.normals import normals_path
from skinhil.model.timeline import Timeline
config = BoardConfig(seed=46, snr_db=10.0, size=(34, 34),
                     schedule_mode=Timeline.SCHEDULE_RANDOM)
link = GoldenLink(False)
board = Board(config, lambda: link)
board.warm_up()
board.queue_session(protocols.SessionReason.START)
for k in range(300):
    link.tick = k
    board.tick()
board.finish(protocols.RunEndReason.DURATION)
data = capture_bytes(link)
print(normals_path(), board.summary().generated, hashlib.sha256(data).hexdigest())
"""


def test_every_path_gives_the_same_spikes_on_a_34x34_board() -> None:
    # 300 ticks of a 34x34 board at 10 dB off the clock (tests/harness/golden.py's link):
    # the same capture, byte for byte, whichever path draws the noise
    runnable = supported_paths()
    code = BOARD_SPIKES.format(tests=str(REPO / "tests"))
    out = {}
    for path in runnable:
        done = _run(code, path)
        assert done.returncode == 0, done.stderr
        out[path] = done.stdout.strip()
    assert [o.split()[0] for o in out.values()] == list(runnable)
    assert all(int(o.split()[1]) > 1000 for o in out.values()), out  # the noise fires
    assert len({o.split()[2] for o in out.values()}) == 1, out


def test_noise_driven_firing_matches_numpy_normals() -> None:
    # 4,000 neurons for 0.3 s at 10 dB under a current that alone never fires them: their
    # spike counts under the kernel's normals and under numpy's (the same model in float64)
    # agree within 5 standard errors
    n, steps, dt_ms, current = 4000, 3000, 0.1, 0.005
    assert not NeuronPopulation(n, seed=1).step_block(np.full((steps, n), current),
                                                      dt_ms * 1e-3).any()
    ours = NeuronPopulation(n, snr_db=10.0, seed=1).step_block(
        np.full((steps, n), current), dt_ms * 1e-3).sum(axis=0)
    rng = np.random.default_rng(2)
    sigma = math.sqrt(10.0**-1 * dt_ms)
    v, u = np.full(n, -65.0), np.full(n, -13.0)
    theirs = np.zeros(n)
    for _ in range(steps):
        v, u = (v + dt_ms * (0.04 * v * v + 5.0 * v + 140.0 - u + 500.0 * current),
                u + dt_ms * 0.02 * (0.2 * v - u))
        v = v + sigma * rng.standard_normal(n)
        u = u + sigma * rng.standard_normal(n)
        fired = v >= 30.0
        theirs += fired
        v[fired] = -65.0
        u[fired] += 9.0
    assert ours.mean() > 0.5  # the noise fires them
    se = math.sqrt(ours.var() / n + theirs.var() / n)
    assert abs(ours.mean() - theirs.mean()) < 5.0 * se, (ours.mean(), theirs.mean())
