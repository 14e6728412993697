"""Writes the task scenarios of this folder (task_*.toml): trials that spread decoders'
scores (neighbouring places and forces, slips at several speeds, close vibration
frequencies), in a seeded shuffled order. Run: python examples/scenarios/make_task_scenarios.py
"""

from __future__ import annotations

import random
from pathlib import Path

HERE = Path(__file__).parent


def _write(name: str, about: str, indenter: str, contacts: list[dict[str, object]]) -> None:
    lines = [f"# {about}", f"# Written by {Path(__file__).name}; the board scores it with "
             "serve --score (protocols/SPEC.md §3.5.4).", "", indenter.strip(), ""]
    for c in contacts:
        lines.append("[[contact]]")
        lines += [f"{k} = {v!r}".replace("'", '"') for k, v in c.items()]
        lines.append("")
    (HERE / f"task_{name}.toml").write_text("\n".join(lines), encoding="utf-8")


def main() -> None:
    rng = random.Random(30)
    places = [(x, y) for x in (-1.0, 0.0, 1.0) for y in (-1.0, 0.0, 1.0)] * 4
    rng.shuffle(places)
    _write("localisation", "36 presses of a 3 mm sphere with 0.5 N for 0.1 s, at the 9 "
           "places of a 1 mm grid around the centre (four times each), one every 0.6 s.",
           '[[indenter]]\nname = "probe"\nshape = "sphere"\nradius_mm = 3.0',
           [{"indenter": "probe", "start_s": round(0.1 + 0.6 * i, 3), "motion": "press",
             "x_mm": x, "y_mm": y, "load_n": 0.5, "ramp_s": 0.01, "hold_s": 0.1}
            for i, (x, y) in enumerate(places)])
    loads = [0.2, 0.3, 0.4, 0.5, 0.6, 0.7] * 6
    rng.shuffle(loads)
    _write("force", "36 presses of a 3 mm sphere at the centre, 0.2 to 0.7 N in steps of "
           "0.1 N (six each: neighbouring forces), held 0.15 s, one every 0.6 s.",
           '[[indenter]]\nname = "probe"\nshape = "sphere"\nradius_mm = 3.0',
           [{"indenter": "probe", "start_s": round(0.1 + 0.6 * i, 3), "motion": "press",
             "load_n": f, "ramp_s": 0.01, "hold_s": 0.15} for i, f in enumerate(loads)])
    speeds = [5.0, 10.0, 20.0, 40.0] * 6
    rng.shuffle(speeds)
    _write("slip", "24 slides of a 5 mm ball held by 1 N and dragged 2 mm along x with low "
           "friction at 5, 10, 20 or 40 mm/s (six each): each sticks, then slips; one every "
           "1.0 s.", '[[indenter]]\nname = "ball"\nshape = "sphere"\nradius_mm = 5.0',
           [{"indenter": "ball", "start_s": round(0.1 + 1.0 * i, 3), "motion": "slide",
             "x_mm": -1.0, "to_x_mm": 1.0, "speed_mm_per_s": v, "load_n": 1.0,
             "ramp_s": 0.03, "dwell_s": 0.1, "mu_static": 0.4, "mu_kinetic": 0.3}
            for i, v in enumerate(speeds)])
    freqs = [50.0, 100.0, 200.0, 300.0] * 8
    rng.shuffle(freqs)
    _write("vibration", "32 presses of a flat 1.5 mm pad, 20 µm deep for 0.3 s, vibrating "
           "8 µm along z at 50, 100, 200 or 300 Hz (eight each), one every 0.6 s.",
           '[[indenter]]\nname = "pad"\nshape = "flat"\nradius_mm = 1.5',
           [{"indenter": "pad", "start_s": round(0.1 + 0.6 * i, 3), "motion": "press",
             "depth_mm": 0.02, "ramp_s": 0.02, "hold_s": 0.3, "vibration_mm": 0.008,
             "vibration_hz": f} for i, f in enumerate(freqs)])


if __name__ == "__main__":
    main()
