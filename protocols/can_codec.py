"""CAN and CAN FD frame layout: encoder and incremental decoder (layout in SPEC.md)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from protocols.records import Ack, CanFrame, Command, DecodeResult, LinkCounters, Marker, Status


class CanEncoder:
    """Board→host (and host→board) CAN frame encoder."""

    def __init__(self, board_id: int = 0, fd: bool = False, step_us: int = 100,
                 max_frame_span_us: int = 1000) -> None:
        self.board_id = board_id
        self.fd = fd

    def events(self, events: np.ndarray, t_end_us: int) -> list[CanFrame]:
        raise NotImplementedError

    def status(self, status: Status) -> list[CanFrame]:
        raise NotImplementedError

    def marker(self, marker: Marker) -> list[CanFrame]:
        raise NotImplementedError

    def command(self, command: Command) -> list[CanFrame]:
        raise NotImplementedError

    def ack(self, ack: Ack) -> list[CanFrame]:
        raise NotImplementedError


class CanDecoder:
    """Incremental decoder of one board's CAN frames."""

    def __init__(self, board_id: int = 0, fd: bool = False) -> None:
        self.board_id = board_id
        self.fd = fd
        self.counters = LinkCounters()

    def feed(self, frames: Iterable[CanFrame]) -> DecodeResult:
        raise NotImplementedError
