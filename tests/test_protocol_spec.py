"""SPEC.md's worked examples are what the encoders produce, and the wire budget helpers."""

from __future__ import annotations

import re

import pytest
from protocol_examples import EXAMPLES, RUN_END, SESSION_RECORDS, SUITE_RECORDS, TASK_CLASSES

from protocols import (
    SPEC_PATH,
    CanDecoder,
    CanFrame,
    SerialDecoder,
    can_frame_seconds,
    serial_seconds,
)
from skinhil.errors import ProtocolError

BLOCK = re.compile(r"<!-- example (\S+) -->\n```text\n(.*?)\n```", re.S)


def test_every_spec_example_matches_the_encoder() -> None:
    blocks = dict(BLOCK.findall(SPEC_PATH.read_text(encoding="utf-8")))
    assert set(blocks) == set(EXAMPLES)
    for name, make in EXAMPLES.items():
        assert blocks[name].strip().upper() == make().strip().upper(), name


def _spec_frames(text: str) -> list[CanFrame]:
    """candump lines (``ID#DATA``, ``ID##<flags>DATA``) as frames."""
    out = []
    for line in text.split():
        ident, data = line.split("#", 1)
        fd = data.startswith("#")
        out.append(CanFrame(int(ident, 16), bytes.fromhex(data[2:] if fd else data), fd))
    return out


def test_session_examples_decode_to_their_records() -> None:
    """The SPEC's SESSION, STIMULUS, RUN_END, SUITE and TASK hex decodes (as written there)
    to the records, on the serial layout and both CAN layouts."""
    blocks = dict(BLOCK.findall(SPEC_PATH.read_text(encoding="utf-8")))
    for records, name in ((list(SESSION_RECORDS), "session"), ([RUN_END], "run-end"),
                          (list(SUITE_RECORDS), "suite"), ([TASK_CLASSES], "task-classes")):
        serial = SerialDecoder()
        assert serial.feed(bytes.fromhex(blocks[f"serial-{name}"])).records == records
        assert serial.counters.frames_ok == len(records)
        for tag, fd in (("can", False), ("canfd", True)):
            dec = CanDecoder(board_id=1, fd=fd)
            assert dec.feed(_spec_frames(blocks[f"{tag}-{name}"])).records == records, tag
            assert dec.counters.malformed == dec.counters.foreign_frames == 0


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
