"""`listen --view`: Debian's headless Chromium loads the live view of a board running on a
pty; the raster draws, counters and decisions advance, the console shows no error."""

from __future__ import annotations

import json
import re
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
from harness.chromium import Chromium
from harness.lab import listening, wait_for_stderr
from harness.serve import ServeProcess

PAGE_STATE = """JSON.stringify({
  updates: view.updates, spikes: view.spikesDrawn, decisions: view.decisionsSeen,
  rows: document.querySelectorAll('#decisions tbody tr').length,
  events: view.lastLink && view.lastLink.events_decoded,
  counters: document.getElementById('counters').innerText,
  answers: document.getElementById('answers-panel').hidden ? null
           : document.getElementById('answers').innerText,
  confusion: document.getElementById('confusion').innerText,
  raster: (() => { const r = document.getElementById('raster').getBoundingClientRect();
                   return [r.left, r.top, r.width, r.height]; })()})"""


def _state(browser: Chromium) -> dict[str, Any]:
    return dict(json.loads(browser.evaluate(PAGE_STATE)))


def _first_decisions(browser: Chromium, timeout_s: float = 60.0) -> dict[str, Any]:
    """The page's state once it shows events and a decision (the page loads, the board
    starts, its kernels load, it plays)."""
    end = time.monotonic() + timeout_s
    state: dict[str, Any] = {}
    while time.monotonic() < end:
        raw = browser.evaluate(PAGE_STATE)  # None until the page's script has run
        state = json.loads(raw) if raw else {}
        if state.get("events") and state.get("decisions"):
            break
        time.sleep(0.25)
    return state


def _client(url: str) -> dict[str, Any]:
    """What the page reported to the server (its errors, what it drew)."""
    return dict(json.loads(urllib.request.urlopen(url + "client", timeout=10).read()))


def _png(path: Path) -> np.ndarray:
    from matplotlib.image import imread

    return np.asarray(imread(str(path)))


def test_chromium_shows_the_live_view_of_a_board_on_a_pty(tmp_path: Path) -> None:
    with listening(tmp_path, "--view", "0", "--psp-sensors", "0,60,120,200", "--answer",
                   ready="live view at") as (listen, board_end):
        url = wait_for_stderr(listen, "live view at").split()[-1]
        assert url.startswith("http://127.0.0.1:")
        board = ServeProcess("--port", str(board_end), "--duration", "9", "--seed", "1",
                             "--snr-db", "10", "--rest", "0.3", "--json")
        try:
            with Chromium() as browser:
                browser.open(url)
                first = _first_decisions(browser)
                t0 = time.monotonic()
                time.sleep(3.0)
                second = _state(browser)
                elapsed = time.monotonic() - t0
                shot = browser.screenshot(tmp_path / "view.png")
                errors = list(browser.console_errors)
                reported = _client(url)
                # both error channels work: a console error is seen over DevTools and the
                # page posts it to the server
                browser.evaluate("console.error('probe ' + 6 * 7)")
                time.sleep(1.0)
                probe = (list(browser.console_errors), _client(url)["errors"])
            assert board.wait(120) == 0, board.stderr
        finally:
            board.kill()
    assert errors == [], errors
    assert reported["errors"] == [], reported
    assert probe == (["probe 42"], ["probe 42"]), probe
    # updates at 10 Hz or faster (a loaded 2-core machine may delay a few)
    assert (second["updates"] - first["updates"]) / elapsed >= 8, (first, second)
    # counters and decisions advance
    assert second["events"] > first["events"] > 0
    assert second["spikes"] > first["spikes"] > 0
    assert second["decisions"] > first["decisions"] or second["rows"] > first["rows"], second
    assert "events decoded" in second["counters"] and "FIFO full" in second["counters"]
    assert "120deg_0.5N" in second["confusion"]
    # the receiver answers the board (--answer): its DECISIONs counted, ACKed by the board
    answered = dict(line.split("\t") for line in second["answers"].splitlines())
    assert int(answered["DECISIONs sent"]) > 0 and int(answered["ACKed"]) > 0, answered
    assert int(answered["NACKed"]) == 0 and int(answered["not sent"]) == 0, answered
    assert reported["state"]["updates"] > 0
    # the raster draws: spike dots on its black canvas
    img = _png(shot)
    left, top, width, height = (int(round(v)) for v in second["raster"])
    # (right of the channel ticks the overlay writes on its left edge; warm pixels only,
    # not the blue onset lines)
    raster = img[top + 2:top + height - 2, left + 48:left + width - 2, :3]
    lit = (raster[..., 0] > 0.3) & (raster[..., 0] > raster[..., 2])
    assert lit.sum() > 200, lit.sum()
    assert lit.any(axis=0).sum() > 50  # dots spread over time (x), not one column
    assert lit.any(axis=1).sum() > 50  # and over channels (y)


POKE_MASS = (6, 19)
"""Top-layer (row, col), 0-based, of the 26x26 skin's poked mass: off the centre, where the
built-in stimuli are, so the map must light the right place and not just the middle."""

POKE = """\
[[stimulus]]
name = "poke"
forces = {{ {mass} = [0.3, 0.3, -0.3] }}
indentation_s = 2.0
decay_tau_s = inf

[[event]]
start_s = 0.6
stimulus = "poke"
"""

LAB_STATE = """view.config && view.xy ? JSON.stringify({
  updates: view.updates, onsets_seen: view.onsetsSeen, onsets_drawn: view.onsetsDrawn,
  map_max_z: view.mapMaxZ, ended: view.ended, psp_sensors: view.config.psp_sensors,
  picked_xy: Array.from(view.xy.slice(2 * view.config.psp_sensors.at(-1),
                                      2 * view.config.psp_sensors.at(-1) + 2)),
  status: document.getElementById('status').textContent,
  banner: document.getElementById('ended-banner').hidden ? null
          : document.getElementById('ended-banner').textContent,
  fits: [document.documentElement.scrollWidth, document.documentElement.scrollHeight,
         window.innerWidth, window.innerHeight],
  map: (() => { const r = document.getElementById('map').getBoundingClientRect();
                return [r.left, r.top, r.width, r.height]; })(),
  marks: (() => { const r = document.getElementById('raster-marks').getBoundingClientRect();
                  return [r.left, r.top, r.width, r.height]; })()}) : null"""


def _wait_state(browser: Chromium, ok: Any, timeout_s: float = 60.0) -> dict[str, Any]:
    """The page's state (:data:`LAB_STATE`) once ``ok(state)``; the last one seen else."""
    end = time.monotonic() + timeout_s
    state: dict[str, Any] = {}
    while time.monotonic() < end:
        raw = browser.evaluate(LAB_STATE)
        state = json.loads(raw) if raw else {}
        if state and ok(state):
            break
        time.sleep(0.1)
    return state


def _box(img: np.ndarray, rect: list[float]) -> np.ndarray:
    left, top, width, height = (int(round(v)) for v in rect)
    return img[top:top + height, left:left + width, :3]


def test_udp_view_and_lsl_at_26x26_fit_a_laptop_and_show_the_touch(
        tmp_path: Path, monkeypatch: Any) -> None:
    """One page load, as a lab runs it: ``listen --udp --view --lsl`` at 26x26 (10,138
    channels) in a 1366x768 window; a board pokes one off-centre mass. The page fits the
    window, the skin map is brightest where the poke is, the onset is drawn on the raster,
    the LSL streams carry the board (link health with its counters), and when the receiver
    stops the page says the run ended (not "reconnecting")."""
    import socket

    import pylsl
    from harness.lab import LOOPBACK_LSL_CFG, chance_model

    cfg = tmp_path / "lsl_api.cfg"
    cfg.write_text(LOOPBACK_LSL_CFG)
    monkeypatch.setenv("LSLAPICFG", str(cfg))
    rows, cols = 26, 26
    model = chance_model(tmp_path, (rows, cols))
    schedule = tmp_path / "poke.toml"
    schedule.write_text(POKE.format(mass=POKE_MASS[0] * cols + POKE_MASS[1] + 1))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    listen = ServeProcess("--udp", f"127.0.0.1:{port}", "--size", "26x26", "--model",
                          str(model), "--json", "--view", "0", "--lsl", "lab34",
                          command="listen")
    board = None
    try:
        url = wait_for_stderr(listen, "live view at").split()[-1]
        with Chromium(1366, 768) as browser:
            browser.open(url)
            # the paper's amplitude: its 0.3 N poke lights its place 4x the rest (2.9x on the
            # default skin, whose small strain spreads the forces wider)
            board = ServeProcess("--udp", f"127.0.0.1:{port}", "--size", "26x26", "--duration",
                                 "3", "--seed", "1", "--snr-db", "10", "--schedule",
                                 str(schedule), "--amplitude", "paper", "--json")
            found = pylsl.resolve_byprop("name", "lab34-link", timeout=60)
            assert len(found) == 1
            inlet = pylsl.StreamInlet(found[0], max_buflen=60)
            inlet.open_stream(10)
            # the poke is on from 0.6 s to 2.6 s: its onset drawn and the map lit
            touched = _wait_state(browser, lambda st: st.get("onsets_drawn", 0) >= 1
                                  and st.get("map_max_z", 0) > 8)
            shot = browser.screenshot(tmp_path / "view-26x26.png")
            # a click on the map at the poke picks the sensor there for the PSP traces
            left, top, w, h = touched["map"]
            browser.evaluate(
                "document.getElementById('map-overlay').dispatchEvent(new MouseEvent('click', "
                f"{{clientX: {left + POKE_MASS[1] / (cols - 1) * w}, "
                f"clientY: {top + POKE_MASS[0] / (rows - 1) * h}, bubbles: true}}))")
            picked = _wait_state(browser, lambda st: len(st["psp_sensors"]) == 8 and
                                 st["psp_sensors"][-1] not in touched["psp_sensors"],
                                 timeout_s=10)
            assert board.wait(120) == 0, board.stderr
            link_samples, _ = inlet.pull_chunk(timeout=2.0, max_samples=1000)
            prov = inlet.info(10).desc().child("provenance")
            board_of_streams = prov.child_value("board")
            listen.interrupt()
            assert listen.wait(60) == 130, listen.stderr
            ended = _wait_state(browser, lambda st: st.get("ended"), timeout_s=10)
            end_shot = browser.screenshot(tmp_path / "view-ended.png")
            errors = list(browser.console_errors)
    finally:
        if board is not None:
            board.kill()
        listen.kill()
    assert errors == [], errors
    # the page fits a 1366x768 laptop: no scrolling either way (the window's viewport is
    # 1366 wide and, less the browser's own bars, at most 768 high)
    width, height, inner_w, inner_h = touched["fits"]
    assert inner_w == 1366 and 600 < inner_h <= 768, touched
    assert width <= inner_w and height <= inner_h, touched
    # the onset is drawn on the raster: the marks' blue line is on the screenshot
    img = _png(shot)
    marks = _box(img, touched["marks"])
    blue = (marks[..., 2] > 0.9) & (marks[..., 1] > 0.7) & (marks[..., 0] < 0.35)
    assert touched["onsets_drawn"] >= 1 and blue.any(axis=0).sum() >= 1, touched
    assert blue.any(axis=1).sum() > 0.8 * marks.shape[0]  # a line over every channel
    # the map lights the poked place: its brightest patch (15x15 px, wider than the rings
    # the overlay draws around the picked PSP sensors) lies on the poked mass
    from scipy.ndimage import uniform_filter

    skin = _box(img, touched["map"]).sum(axis=2)
    h, w = skin.shape
    py, px = POKE_MASS[0] / (rows - 1) * h, POKE_MASS[1] / (cols - 1) * w
    yy, xx = np.mgrid[0:h, 0:w]
    near = np.hypot(yy - py, xx - px) < 0.06 * w  # about the poked mass's two cells
    cy, cx = np.unravel_index(np.argmax(uniform_filter(skin, 15)), skin.shape)
    assert np.hypot(cy - py, cx - px) < 0.06 * w, ((cy, cx), (py, px))
    assert skin[near].mean() > 4 * skin[~near].mean(), (skin[near].mean(), skin[~near].mean())
    # the picked sensor (the newest PSP trace) lies at the poked mass
    assert picked["psp_sensors"][:7] == touched["psp_sensors"][1:], (picked, touched)
    col, row = picked["picked_xy"]
    assert abs(col - POKE_MASS[1]) <= 0.5 and abs(row - POKE_MASS[0]) <= 0.5, picked
    # LSL on UDP: the link-health stream of this board, counting its events
    summary = listen.summary()
    (key, info), = summary["boards"].items()
    assert board_of_streams == key
    decoded = [s[0] for s in link_samples]
    assert decoded and max(decoded) == info["link"]["events_decoded"] == \
        board.summary()["generated"] > 0
    # the end of the run: said on the page, not "reconnecting"
    assert ended["ended"] and ended["status"].startswith("run ended"), ended
    assert ended["banner"] and "receiver stopped" in ended["banner"], ended
    assert end_shot.exists()


GRASP_STATE = """view.grasp ? JSON.stringify({
  points: view.grasp.points, ended: view.ended,
  hidden: document.getElementById('grasp-panel').hidden,
  max: Object.fromEntries(['grip_n', 'normal_n', 'load_n', 'slip_mm', 'slip'].map(
    (k) => [k, Math.max(0, ...view.grasp[k])])),
  min_grip: Math.min(...view.grasp.grip_n.filter((g) => g !== null)),
  gripped: view.grasp.grip_n.filter((g) => g !== null).length,
  gripped_after_drop: view.grasp.t_us.filter((t, i) => view.grasp.grip_n[i] !== null
    && view.grasp.outcomes.some((o) => o.lift === view.grasp.lift[i] && !o.held && t >= o.t_us)
  ).length,
  outcomes: view.grasp.outcomes,
  canvas: (() => { const r = document.getElementById('grasp').getBoundingClientRect();
                   return [r.left, r.top, r.width, r.height]; })()}) : null"""


def test_grasp_demo_view_plots_grip_load_and_slip(tmp_path: Path) -> None:
    """``demo --task grasp --lifts 2 --controller off --view``: the page's grasp panel plots
    the board's truth: the hand's constant 0.3 N grip until each object drops (none after),
    the load up to the weight and the
    pull, the slip distance past the 1 mm drop, both lifts marked dropped, as the demo's
    scores say; the lines are on the screenshot."""
    demo = ServeProcess("--task", "grasp", "--lifts", "2", "--controller", "off", "--view",
                        "0", command="demo")
    try:
        url = wait_for_stderr(demo, "live view at").split()[-1]
        with Chromium() as browser:
            browser.open(url)
            end = time.monotonic() + 60
            state: dict[str, Any] = {}
            while time.monotonic() < end:
                raw = browser.evaluate(GRASP_STATE)
                state = json.loads(raw) if raw else {}
                if len(state.get("outcomes", [])) == 2 or demo.exited:
                    break
                time.sleep(0.2)
            assert demo.wait(60) == 0, demo.stderr
            time.sleep(0.5)  # the last update drawn
            state = json.loads(browser.evaluate(GRASP_STATE))
            shot = browser.screenshot(tmp_path / "grasp-view.png")
            errors = list(browser.console_errors)
    finally:
        demo.kill()
    assert errors == [], errors
    text = "".join(line.get("text", "") for line in demo.lines)
    slid = [float(s) for s in re.findall(r"DROP .* (\d+\.\d+) mm", text)]
    assert len(slid) == 2, text
    assert not state["hidden"] and state["points"] > 150, state  # 2.35 s of 10 ms points
    assert state["min_grip"] == state["max"]["grip_n"] == 0.3, state  # the hand's low grip
    # the grip while the object is held, none after it dropped: 0.2-0.5 s of each lift
    assert 40 <= state["gripped"] <= 100 and state["gripped_after_drop"] == 0, state
    assert 0.64 <= state["max"]["load_n"] <= 0.65, state  # m·g + the pull: 0.49 + 0.15 N
    assert 0.2 < state["max"]["normal_n"] < 0.4, state
    assert state["max"]["slip"] == 3 and round(state["max"]["slip_mm"], 2) == max(slid), state
    assert [(o["lift"], o["held"]) for o in state["outcomes"]] == [(1, False), (2, False)]
    # the lines on the panel: grip (#fc6), load (#9cf) and the drop marks (#f66)
    panel = _png(shot)
    left, top, width, height = (int(round(v)) for v in state["canvas"])
    px = panel[top + 14:top + height - 2, left:left + width, :3]

    def near(rgb: tuple[int, int, int]) -> int:
        """Columns (board time) where the colour ``rgb`` is drawn."""
        return int((np.abs(px - np.array(rgb) / 255).max(axis=2) < 0.12).any(axis=0).sum())

    # 2.35 s of the panel's 10 s: about 170 columns of the load, 45 of the grip (held)
    grip, load = near((0xff, 0xcc, 0x66)), near((0x99, 0xcc, 0xff))
    assert load > 100 and 25 < grip < load / 2, (grip, load)
    assert near((0xff, 0x66, 0x66)) >= 2  # the drop marks
