"""The wire codecs stand alone: a capture decodes with ``protocols`` in an interpreter where
``skinhil`` and ``firmware_sim`` cannot be imported (the layering itself is checked by
import-linter's contracts, tests/test_architecture.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

_STANDALONE = """
import importlib.abc, json, sys

class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("skinhil", "firmware_sim"):
            raise ImportError(f"{name} is not installed here")
        return None

sys.meta_path.insert(0, Refuse())
try:
    import skinhil  # noqa: F401
except ImportError:
    pass
else:
    raise SystemExit("skinhil is still importable")
import protocols
dec = protocols.SerialDecoder()
data = open(sys.argv[1], "rb").read()
events, records = [], []
for i in range(0, len(data), 97):
    res = dec.feed(data[i:i + 97])
    events += [(int(e["t"]), int(e["addr"])) for e in res.events]
    records += [type(r).__name__ for r in res.records]
print(json.dumps({"events": events, "records": records, "ok": dec.counters.frames_ok,
                  "bad": dec.counters.crc_errors + dec.counters.malformed,
                  "loaded": sorted({m.split(".")[0] for m in sys.modules} & {"skinhil",
                                                                          "firmware_sim"})}))
"""


def test_protocols_decodes_a_capture_without_skinhil(tmp_path: Path) -> None:
    """A recorded serial capture (events, a marker, a status) decodes with ``protocols`` alone
    in an interpreter where ``skinhil`` and ``firmware_sim`` cannot be imported."""
    from protocols import Marker, MarkerPhase, SerialEncoder, Status
    from skinhil.events import make_events

    rng = np.random.default_rng(7)
    t = np.sort(rng.integers(0, 2_000, 300)) * 100
    ev = make_events(t, rng.integers(0, 338, 300))
    ev = ev[np.lexsort((ev["addr"], ev["t"]))]  # the wire's order: by time, then channel
    enc = SerialEncoder()
    capture = enc.events(ev[:150], int(t[150]))
    capture += enc.marker(Marker(int(t[150]), 4, MarkerPhase.ONSET))
    capture += enc.events(ev[150:], 200_000)
    capture += enc.status(Status(t_us=200_000, events_generated=300, events_sent=300,
                                 events_dropped=0, events_queued=0, late_ticks=0, rx_errors=0,
                                 running=True))
    path = tmp_path / "capture.bin"
    path.write_bytes(capture)
    res = subprocess.run([sys.executable, "-c", _STANDALONE, str(path)], capture_output=True,
                         text=True, timeout=300, check=False)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out["loaded"] == []
    assert out["events"] == [[int(a), int(b)] for a, b in zip(ev["t"], ev["addr"], strict=True)]
    assert out["records"] == ["Marker", "Status"]
    assert out["bad"] == 0 and out["ok"] > 2
