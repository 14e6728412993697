"""The replayed stream: the recording unchanged, until the player inserts an answer.

A player answers each host command with an ACK of its own, between two packets (frames) of
the recording; the ACK takes the next board sequence number and every later recorded packet
or frame is renumbered by one more (SPEC.md "Capture files"), so a decoder sees an unbroken
count. With no answer inserted, :meth:`out` returns each unit as it was recorded.
"""

from __future__ import annotations

from typing import Any, Generic, TypeVar

from protocols.records import CanFrame
from protocols.resequence import (
    can_frame_seq,
    can_frame_with_seq,
    serial_packet_seq,
    serial_packet_with_seq,
)

U = TypeVar("U")

MAX_OPEN_BYTES = 2064
"""Bytes of a packet still open (no delimiter yet) kept to read its sequence number; a
longer run is no packet (SPEC.md §6 rule 3)."""


class ReplayStream(Generic[U]):
    """What both streams keep: the answers waiting, how many went in, the last number."""

    def __init__(self) -> None:
        self._shift = 0
        self._last_seq: int | None = None
        self._answers: list[U] = []

    @property
    def shift(self) -> int:
        """Answers inserted so far: what every later packet's (frame's) sequence number is
        advanced by."""
        return self._shift

    def answer(self, unit: U) -> None:
        """Insert ``unit`` (an ACK packet or frame) at the next packet (frame) boundary."""
        self._answers.append(unit)


class SerialReplayStream(ReplayStream[bytes]):
    """A recorded serial (or UDP) byte stream, with answer packets inserted at packet
    boundaries and the packets after them renumbered."""

    def __init__(self) -> None:
        super().__init__()
        self._open = b""
        """The start of a packet already sent as recorded, its delimiter still to come."""
        self._carry = b""
        """The start of a packet held back: it will be renumbered once whole."""

    def _note(self, packet: bytes) -> None:
        seq = serial_packet_seq(packet)
        if seq is not None:
            self._last_seq = seq

    def _track(self, unit: bytes) -> None:
        """Follow ``unit`` sent as recorded: the last whole packet's number, the open one."""
        joined = self._open + unit
        cut = joined.rfind(0)
        if cut < 0:
            self._open = joined[-MAX_OPEN_BYTES:]
            return
        last = joined[:cut].rstrip(b"\0").rsplit(b"\0", 1)[-1]
        if last:
            self._note(last)
        self._open = joined[cut + 1:][-MAX_OPEN_BYTES:]

    def _renumber(self, packets: bytes) -> bytes:
        out = []
        for packet in packets.split(b"\0")[:-1]:
            seq = serial_packet_seq(packet) if packet else None
            if seq is None:  # an idle delimiter or bytes of no packet: as recorded
                out.append(packet + b"\0")
                continue
            new = (seq + self._shift) % 256
            out.append(serial_packet_with_seq(packet, new))
            self._last_seq = new
        return b"".join(out)

    def out(self, unit: bytes) -> list[bytes]:
        """What to send for the recorded ``unit``: payloads in order (answers in one of
        their own, so a datagram link keeps the recorded datagrams apart from them)."""
        if not self._shift and not self._answers and not self._carry:
            self._track(unit)
            return [unit]
        sends = []
        data = bytes(unit)
        if self._open:  # finish the packet begun as recorded
            cut = data.find(0)
            if cut < 0:
                self._open += data
                return [data]
            self._note(self._open + data[:cut])
            sends.append(data[:cut + 1])
            self._open, data = b"", data[cut + 1:]
        data, self._carry = self._carry + data, b""
        if self._answers:
            answers = []
            for packet in self._answers:
                seq = 0 if self._last_seq is None else (self._last_seq + 1) % 256
                answers.append(serial_packet_with_seq(packet, seq))
                self._last_seq = seq
                self._shift += 1
            self._answers.clear()
            sends.append(b"".join(answers))
        end = data.rfind(0) + 1
        if end:
            sends.append(self._renumber(data[:end]))
        self._carry = data[end:]
        return [s for s in sends if s]

    def flush(self) -> list[bytes]:
        """At the end: answers still pending and any packet held back."""
        sends = self.out(b"") if self._answers else []
        if self._carry:
            sends.append(self._carry)
            self._carry = b""
        return sends


class CanReplayStream(ReplayStream[CanFrame]):
    """Recorded CAN frames, with answer frames inserted between them and the frames after
    them renumbered."""

    def out(self, frame: Any) -> list[CanFrame]:
        """The frames to send for the recorded ``frame``: answers first, then it."""
        sends = []
        for answer in self._answers:
            seq = 0 if self._last_seq is None else self._last_seq + 1
            sends.append(can_frame_with_seq(answer, seq))
            self._last_seq = can_frame_seq(sends[-1])
            self._shift += 1
        self._answers.clear()
        if frame is not None:
            if self._shift:
                frame = can_frame_with_seq(frame, can_frame_seq(frame) + self._shift)
            sends.append(frame)
            self._last_seq = can_frame_seq(frame)
        return sends

    def flush(self) -> list[CanFrame]:
        """At the end: answers still pending."""
        return self.out(None)
