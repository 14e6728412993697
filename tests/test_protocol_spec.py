"""SPEC.md's worked examples are what the encoders produce, and the wire budget helpers."""

from __future__ import annotations

import re

import pytest
from protocol_examples import EXAMPLES

from protocols import SPEC_PATH, CanFrame, can_frame_seconds, serial_seconds
from skinhil.errors import ProtocolError

BLOCK = re.compile(r"<!-- example (\S+) -->\n```text\n(.*?)\n```", re.S)


def test_every_spec_example_matches_the_encoder() -> None:
    blocks = dict(BLOCK.findall(SPEC_PATH.read_text(encoding="utf-8")))
    assert set(blocks) == set(EXAMPLES)
    for name, make in EXAMPLES.items():
        assert blocks[name].strip().upper() == make().strip().upper(), name


def test_wire_time() -> None:
    assert serial_seconds(9216, 921600) == pytest.approx(0.1)
    classic = can_frame_seconds(CanFrame(0x60, bytes(8)), 1_000_000)
    assert 1 / classic == pytest.approx(7407, rel=0.01)  # 135 bits, worst-case stuffing
    fd = can_frame_seconds(CanFrame(0x60, bytes(64), True), 1_000_000, 2_000_000)
    assert 2500 < 1 / fd < 3300
    assert can_frame_seconds(CanFrame(0x60, bytes(4)), 1_000_000) < classic
    with pytest.raises(ProtocolError):
        can_frame_seconds(CanFrame(0x60, bytes(9)), 1_000_000)
    with pytest.raises(ProtocolError):
        serial_seconds(10, 0)
