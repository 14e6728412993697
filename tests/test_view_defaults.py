"""The live view at the defaults (6x6 skin, 10 dB): a page opened seconds into the run draws
the server's history at once; the skin map, each place's rate above its sensors' own
baselines, is brightest where the board's stimuli press (mass M15) in the page's data and on
its pixels; the operator's truth file adds its onsets; onset labels do not overlap; the
decisions' latency column is not clipped. Plus the map's statistics and the truth file's
reading without a browser."""

from __future__ import annotations

import json
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
from harness.chromium import Chromium
from harness.lab import listening, wait_for_stderr
from harness.serve import ServeProcess

from skinhil.model.geometry import build_mesh
from skinhil.model.skin import SkinParams
from skinhil.view.feed import grid_xy
from skinhil.view.rate_map import TOUCH_Z, RateMap
from skinhil.view.truth_onsets import truth_onsets

PRESSED = (2.0, 2.0)
"""(column, row) in grid units of M15, where the built-in direction conditions push."""

NEAR = 1.25
"""Grid units around :data:`PRESSED` that count as the touched place."""

TRUTH_T_US = 4_321_000
"""Board time of the hand-written truth file's contact onset."""

STATE = """view.config && view.mapZ ? JSON.stringify({
  z: Array.from(view.mapZ), max_z: view.mapMaxZ, shape: view.config.map_shape,
  history: view.history, updates: view.updates, spikes: view.spikesDrawn,
  onsets: view.onsetsSeen, boxes: view.labelBoxes, thinned: view.labelsThinned,
  truth: view.markers.filter((m) => m.source === 'truth').map((m) => m.label),
  latency: Array.from(document.querySelectorAll(
      '#decisions td:last-child, #decisions th:last-child')).map(
      (td) => [td.scrollWidth, td.clientWidth, td.getBoundingClientRect().right]),
  right: window.innerWidth,
  map: (() => { const r = document.getElementById('map').getBoundingClientRect();
                return [r.left, r.top, r.width, r.height]; })()}) : null"""


def _near_mask(shape: tuple[int, int]) -> np.ndarray:
    """The places (half-cells) within :data:`NEAR` of :data:`PRESSED`."""
    by, bx = np.mgrid[0:shape[0], 0:shape[1]]
    return np.hypot((bx + 0.5) / 2 - PRESSED[0], (by + 0.5) / 2 - PRESSED[1]) <= NEAR


def _wait_board_time(url: str, t_us: int, timeout_s: float = 60.0) -> None:
    """Read the view's stream until its board time reaches ``t_us``."""
    end = time.monotonic() + timeout_s
    with urllib.request.urlopen(url + "events", timeout=10) as resp:
        for raw in resp:
            line = raw.decode()
            if line.startswith("data: ") and json.loads(line[6:]).get("t_board_us", 0) >= t_us:
                return
            assert time.monotonic() < end, "the board did not reach its time"


def _state(browser: Chromium) -> dict[str, Any]:
    raw = browser.evaluate(STATE)
    return json.loads(raw) if raw else {}


def test_a_late_page_at_the_defaults_shows_the_touch(tmp_path: Path) -> None:
    truth = tmp_path / "truth.jsonl"
    with listening(tmp_path, "--view", "0", "--view-truth", str(truth),
                   ready="live view at") as (listen, board_end):
        url = wait_for_stderr(listen, "live view at").split()[-1]
        board = ServeProcess("--port", str(board_end), "--duration", "9", "--seed", "1",
                             "--snr-db", "10", "--json")
        try:
            board.wait_ready()
            _wait_board_time(url, 3_000_000)  # the page opens 3 s into the run
            truth.write_text(json.dumps({"type": "trial", "task": "localisation",
                                         "t_us": TRUTH_T_US, "contact": 1}) + "\n")
            with Chromium(1366, 768) as browser:
                browser.open(url)
                first: dict[str, Any] = {}
                end = time.monotonic() + 20
                while not first and time.monotonic() < end:
                    first = _state(browser)
                    time.sleep(0.05)
                samples, shot, peak = [], None, 0.0
                end = time.monotonic() + 6.0
                while time.monotonic() < end and not board.exited:
                    state = _state(browser)
                    samples.append(np.asarray(state["z"]).reshape(state["shape"]))
                    if state["max_z"] > max(peak, 8.0):  # the strongest touch seen: its picture
                        peak = state["max_z"]
                        shot = browser.screenshot(tmp_path / "touch.png")
                        shot_state = state
                    time.sleep(0.1)
                last = _state(browser)
                errors = list(browser.console_errors)
            assert board.wait(60) == 0, board.stderr
        finally:
            board.kill()
    assert errors == [], errors
    # a page opened late is not empty: the history's seconds drawn before any update
    assert first["history"]["updates"] >= 20 and first["history"]["spikes"] > 0, first
    assert first["history"]["markers"] > 0, first
    # the touched place is brighter than the rest, over the run and at its strongest
    z = np.mean(samples, axis=0)
    near = _near_mask(z.shape)
    assert z[near].mean() > 1.0 > z[~near].mean(), (z[near].mean(), z[~near].mean())
    assert near[np.unravel_index(np.argmax(z), z.shape)], z.round(1)
    assert shot is not None, peak
    from matplotlib.image import imread

    img = np.asarray(imread(str(shot)))[..., :3].sum(axis=2)
    left, top, width, height = (int(round(v)) for v in shot_state["map"])
    skin = img[top:top + height, left:left + width]
    yy, xx = np.mgrid[0:height, 0:width]
    cols, rows = (shot_state["shape"][1] + 2) / 2, (shot_state["shape"][0] + 2) / 2
    where = np.hypot(xx / width * (cols - 1) - PRESSED[0],
                     yy / height * (rows - 1) - PRESSED[1]) <= NEAR
    assert skin[where].mean() > 2 * skin[~where].mean(), (skin[where].mean(),
                                                          skin[~where].mean())
    # the operator's truth is drawn beside the markers; labels do not overlap
    assert "contact 1" in last["truth"], last["truth"]
    boxes = last["boxes"]
    assert last["onsets"] > 0 and boxes
    for i, (x0, y0, w0, _) in enumerate(boxes):
        for x1, y1, w1, _ in boxes[i + 1:]:
            assert y0 != y1 or x0 + w0 <= x1 or x1 + w1 <= x0, boxes
    # the latency column is whole and inside the window
    assert last["latency"], last
    for scroll, client, right in last["latency"]:
        assert scroll <= client and right <= last["right"], last["latency"]


def test_the_map_stands_a_touch_out_of_the_noise_of_each_sensor() -> None:
    """Poisson noise at 1 Hz per sensor with one place's sensors at 30 Hz for 0.3 s: that
    place's z is far above :data:`TOUCH_Z` and every other place's below it most of the
    time; the touch does not raise its own baseline."""
    p = SkinParams()
    xy = grid_xy(build_mesh(p.spacing_m, p.layer_gap_m))
    rate_map = RateMap(xy, (6, 6))
    touched = np.flatnonzero(np.hypot(xy[:, 0] - 2.2, xy[:, 1] - 2.2) < 0.4)
    rng = np.random.default_rng(5)
    rates = np.full(xy.shape[0], 1.0)
    peaks: dict[int, float] = {}
    rest_over, t = 0, 0
    for step in range(300):  # 30 s of 0.1 s updates, a touch every 3 s
        t += 100_000
        on = step % 30 in (10, 11, 12)
        hz = rates.copy()
        if on:
            hz[touched] = 30.0
        rate_map.add(np.repeat(np.arange(hz.size), rng.poisson(hz * 0.1)))
        rate_map.advance(t)
        bins = rate_map.bin_of[touched]
        mask = np.ones(rate_map.z.shape, bool)  # the places whose pool holds no touched sensor
        for b in bins:
            y, x = divmod(int(b), rate_map.cols)
            mask[max(0, y - 1):y + 2, max(0, x - 1):x + 2] = False
        mask = mask.ravel()
        if on and step > 30:
            peaks[step // 30] = max(peaks.get(step // 30, 0.0),
                                    float(rate_map.z.ravel()[bins].max()))
        if step % 30 > 20:
            rest_over += int((rate_map.z.ravel()[mask] >= TOUCH_Z).sum())
    assert len(peaks) == 9 and min(peaks.values()) > 3 * TOUCH_Z, peaks
    assert rest_over < 0.01 * 90 * mask.sum(), (rest_over, mask.sum())
    assert abs(rate_map.baseline_hz()[touched].mean() - 1.0) < 0.3


def test_truth_onsets_from_the_serve_truth_file() -> None:
    lines = [json.dumps({"type": "marker", "t_us": 1000, "stimulus_id": 3, "phase": "onset"}),
             json.dumps({"type": "marker", "t_us": 251000, "stimulus_id": 3, "phase": "end"}),
             json.dumps({"type": "trial", "task": "localisation", "t_us": 5000, "contact": 2}),
             json.dumps({"type": "trial", "task": "force", "t_us": 5000, "contact": 2}),
             "not json", "[1, 2]", json.dumps({"type": "other", "t_us": 9})]
    onsets = truth_onsets(lines)
    assert [(o["t_us"], o["phase"], o["label"], o["stimulus_id"]) for o in onsets] == [
        (1000, "onset", None, 3), (5000, "onset", "contact 2", None),
        (251000, "end", None, 3)]


def test_view_truth_needs_the_view() -> None:
    from harness.serve import RUN_DIR, serve_env

    done = subprocess.run([sys.executable, "-m", "skinhil", "listen", "--port", "/dev/null",
                           "--model", "none.npz", "--view-truth", "truth.jsonl"],
                          cwd=RUN_DIR, env=serve_env(), capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "skinhil: error: --view-truth FILE draws the truth on the live view: add --view PORT"]
