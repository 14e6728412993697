"""Serial packet stream: encoder and incremental decoder (layout in SPEC.md)."""

from __future__ import annotations

import numpy as np

from protocols.records import Ack, Command, DecodeResult, LinkCounters, Marker, Status


class SerialEncoder:
    """Board→host (and host→board) serial packet encoder."""

    def __init__(self, step_us: int = 100, max_packet_span_us: int = 1000) -> None:
        self.step_us = step_us
        self.max_packet_span_us = max_packet_span_us

    def events(self, events: np.ndarray, t_end_us: int) -> bytes:
        raise NotImplementedError

    def status(self, status: Status) -> bytes:
        raise NotImplementedError

    def marker(self, marker: Marker) -> bytes:
        raise NotImplementedError

    def command(self, command: Command) -> bytes:
        raise NotImplementedError

    def ack(self, ack: Ack) -> bytes:
        raise NotImplementedError


class SerialDecoder:
    """Incremental decoder of the serial packet stream."""

    def __init__(self) -> None:
        self.counters = LinkCounters()

    def feed(self, data: bytes) -> DecodeResult:
        raise NotImplementedError
