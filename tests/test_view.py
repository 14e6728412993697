"""`listen --view`: Debian's headless Chromium loads the live view of a board running on a
pty; the raster draws, counters and decisions advance, the console shows no error."""

from __future__ import annotations

import json
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
    raster = img[top + 2:top + height - 2, left + 2:left + width - 2, :3]
    lit = raster.max(axis=2) > 0.3
    assert lit.sum() > 200, lit.sum()
    assert lit.any(axis=0).sum() > 50  # dots spread over time (x), not one column
    assert lit.any(axis=1).sum() > 50  # and over channels (y)
