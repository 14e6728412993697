"""The board's behaviour pinned: four sessions played off the clock (``harness/golden.py``)
give, byte for byte, the captures recorded in ``tests/golden/``; their scores keep every
recorded value (a score may gain fields, never change one)."""

from __future__ import annotations

import json
from typing import Any

import pytest
from harness.golden import GOLDEN_DIR, play, sessions


def _kept(recorded: Any, now: Any, where: str = "scores") -> None:
    if isinstance(recorded, dict):
        assert isinstance(now, dict), where
        for key, value in recorded.items():
            assert key in now, f"{where}.{key} is gone"
            _kept(value, now[key], f"{where}.{key}")
    else:
        assert now == recorded, f"{where}: {now!r}, recorded {recorded!r}"


@pytest.mark.parametrize("session", sessions(), ids=lambda s: s.name)
def test_session_is_byte_identical_to_its_capture(session: Any) -> None:
    data, scores = play(session)
    expected = (GOLDEN_DIR / f"{session.name}.bin").read_bytes()
    first = next((i for i, (a, b) in enumerate(zip(data, expected, strict=False)) if a != b),
                 min(len(data), len(expected)))
    assert data == expected, f"{len(data)} bytes, recorded {len(expected)}; first differ at {first}"
    _kept(json.loads((GOLDEN_DIR / f"{session.name}.json").read_text(encoding="utf-8")), scores)
