"""Wire protocols of skinhil: pure codecs (no I/O) shared by the board and the receiver.

- Serial: :class:`SerialEncoder` / :class:`SerialDecoder` (COBS-framed packets, CRC-16).
- CAN and CAN FD: :class:`CanEncoder` / :class:`CanDecoder` over :class:`CanFrame`.
- Records: :class:`Status`, :class:`Marker`, :class:`Command`, :class:`Decision` and
  :class:`Answer` (the decoder under test's answers to a task), :class:`Ack`; the session
  records :class:`Session`, :class:`StimulusEntry` (one row of the stimulus table),
  :class:`SuiteEntry` and :class:`TaskEntry` (the suite case and the terms of each task it
  poses) and :class:`RunEnd`.
- Wire time: :func:`serial_seconds`, :func:`can_frame_seconds`.

The normative layout is ``protocols/SPEC.md``; the CAN databases are ``protocols/skinhil.dbc``
(classic) and ``protocols/skinhil_fd.dbc`` (FD).
"""

from __future__ import annotations

from pathlib import Path

import protocols.kernel_cache  # noqa: F401  (numba's cache keyed on the sources, before any kernel)
from protocols.answer_layouts import ANSWER_LAYOUTS, AnswerLayout, register_answer_layout
from protocols.budget import can_frame_seconds, serial_seconds
from protocols.can_codec import CanDecoder, CanEncoder, full_events_frame
from protocols.constants import N_CHANNELS
from protocols.record_fields import answer_range
from protocols.records import (
    ANSWER_SCALE,
    ANSWER_UNITS,
    Ack,
    Answer,
    CanFrame,
    Command,
    CommandCode,
    Decision,
    DecodeResult,
    LinkCounters,
    Marker,
    MarkerPhase,
    NackReason,
    Record,
    RunEnd,
    RunEndReason,
    Session,
    SessionReason,
    SessionRecord,
    Status,
    StimulusEntry,
    SuiteEntry,
    Task,
    TaskEntry,
)
from protocols.serial_codec import MAX_PACKET_BYTES, SerialDecoder, SerialEncoder
from protocols.session_layout import table_digest

DBC_PATH = Path(__file__).with_name("skinhil.dbc")
"""The CAN database (DBC) of the classic CAN layout, for board id 0."""

DBC_FD_PATH = Path(__file__).with_name("skinhil_fd.dbc")
"""The CAN database (DBC) of the CAN FD layout, for board id 0."""

SPEC_PATH = Path(__file__).with_name("SPEC.md")
"""The normative protocol specification."""

CONFORMANCE_PATH = Path(__file__).with_name("conformance.json")
"""The conformance vectors of the serial stream (SPEC.md §11): input bytes and what a decoder
must output."""

__all__ = [
    "CONFORMANCE_PATH", "DBC_FD_PATH", "DBC_PATH", "N_CHANNELS", "SPEC_PATH", "Ack",
    "CanDecoder", "CanEncoder", "CanFrame", "RunEnd", "RunEndReason", "Session",
    "SessionReason", "SessionRecord", "StimulusEntry", "SuiteEntry", "TaskEntry",
    "table_digest",
    "Command", "CommandCode", "DecodeResult", "Decision", "LinkCounters", "Marker", "MarkerPhase",
    "MAX_PACKET_BYTES", "NackReason", "Record", "SerialDecoder", "SerialEncoder", "Status",
    "ANSWER_LAYOUTS", "ANSWER_SCALE", "ANSWER_UNITS", "Answer", "AnswerLayout", "Task",
    "answer_range", "register_answer_layout",
    "can_frame_seconds", "full_events_frame", "serial_seconds",
]
