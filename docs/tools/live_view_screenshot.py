"""Take the live view's picture (docs/live-view.png): ``skinhil demo --view`` at its
defaults (6x6 skin, 10 dB, seed 1), in Debian's headless Chromium (1366x768, a laptop's
screen), at the first moment past ``--at`` seconds of board time when a touch lights the
skin map (its brightest place at ``--min-z`` or above), so the picture shows what a user
sees when the board presses.

    python docs/tools/live_view_screenshot.py [--out docs/live-view.png] [--at 12]

It drives Chromium with the tests' DevTools client (tests/harness/chromium.py) and runs
the demo from this checkout; the demo trains and caches its decoder on first use.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))

from harness.chromium import Chromium  # noqa: E402  (the tests' client, on the path above)

STATE = """view.config && view.mapZ ? JSON.stringify({
  t_s: view.nowUs * 1e-6, max_z: view.mapMaxZ, decisions: view.decisionsSeen}) : null"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "live-view.png")
    ap.add_argument("--at", type=float, default=12.0, help="board seconds before the picture")
    ap.add_argument("--min-z", type=float, default=12.0,
                    help="the skin map's brightest place at least this z (a touch)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds to give up after")
    args = ap.parse_args()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))])}
    demo = subprocess.Popen([sys.executable, "-m", "skinhil", "demo", "--view", "0",
                             "--duration", str(args.at + 20), "--quiet"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=REPO)
    try:
        assert demo.stderr is not None
        url = ""
        for line in demo.stderr:
            if "live view at" in line:
                url = line.split()[-1]
                break
        if not url:
            print("the demo did not start its live view", file=sys.stderr)
            return 1
        end = time.monotonic() + args.timeout
        with Chromium(1366, 768) as browser:
            browser.open(url)
            while time.monotonic() < end and demo.poll() is None:
                raw = browser.evaluate(STATE)
                state = json.loads(raw) if raw else {}
                if state and state["t_s"] >= args.at and state["max_z"] >= args.min_z:
                    browser.screenshot(args.out)
                    print(f"{args.out}: board time {state['t_s']:.2f} s, map peak z "
                          f"{state['max_z']:.1f}, {state['decisions']} decisions shown")
                    return 0
                time.sleep(0.05)
        print("no touch lit the map in time (the demo ended or --timeout)", file=sys.stderr)
        return 1
    finally:
        demo.terminate()
        demo.wait(30)


if __name__ == "__main__":
    sys.exit(main())
