"""A fault-injecting wrapper around any :class:`~skinhil.transports.base.Transport`.

Wrap the receiving (or sending) end of a link to see how a decoder copes with a bad link::

    link = FaultyTransport(SerialTransport("/dev/pts/3"), FaultParams(corrupt_byte_p=1e-4))

Faults are applied to what passes through :meth:`recv` and :meth:`send`, seeded, and counted
in :attr:`FaultyTransport.injected`:

- a CAN link (payloads are lists of frames): each frame is dropped with probability
  ``drop_p``, else duplicated with ``duplicate_p``; each data byte is bit-flipped with
  ``corrupt_byte_p``; a frame is held back ``delay_s`` (s) with ``delay_p``;
- a serial link (payloads are bytes), ``serial_unit="packet"`` (default): the unit is one
  packet of the zero-delimited stream (its bytes up to and including the ``0x00``
  delimiter; a partial packet waits for the rest of it): each packet is dropped with
  ``drop_p``, else duplicated with ``duplicate_p``; each byte before the delimiter is
  bit-flipped (one random non-zero XOR mask) with ``corrupt_byte_p`` — the delimiter is
  kept, so every damaged packet is exactly one lost frame; a packet is held back
  ``delay_s`` with ``delay_p``;
- a serial link with ``serial_unit="chunk"``: the same on whatever each read returned
  (a burst loss, as when a UART overruns; corruption may hit delimiters too).

Delayed items come out in order behind the items already due, so delays never reorder the
stream (as on a real link); they only add latency.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field, replace
from numbers import Integral
from typing import Any, ClassVar

import numpy as np

from skinhil.transports.base import Transport, WrappedTransport
from skinhil.validation import (
    PROBABILITY,
    Constraints,
    Interval,
    StrOptions,
    non_negative,
    validate_params,
)


@dataclass(frozen=True)
class FaultParams:
    """Probabilities (0..1) per frame/chunk (drop, duplicate, delay) and per byte (corrupt)."""

    drop_p: float = 0.0
    corrupt_byte_p: float = 0.0
    duplicate_p: float = 0.0
    delay_p: float = 0.0
    delay_s: float = 0.0
    seed: int = 0
    serial_unit: str = "packet"
    """Serial links: ``"packet"`` (zero-delimited frames) or ``"chunk"`` (reads)."""

    _parameter_constraints: ClassVar[Constraints] = {
        "drop_p": PROBABILITY,
        "corrupt_byte_p": PROBABILITY,
        "duplicate_p": PROBABILITY,
        "delay_p": PROBABILITY,
        "delay_s": non_negative("s"),
        "seed": Interval(Integral, 0, None, closed="left"),
        "serial_unit": StrOptions(("packet", "chunk")),
    }

    def __post_init__(self) -> None:
        validate_params(self)


@dataclass
class InjectedFaults:
    """What the wrapper did: units seen, dropped, duplicated, delayed; bytes corrupted."""

    units_seen: int = 0
    units_dropped: int = 0
    bytes_dropped: int = 0
    """Payload bytes in the dropped units (serial: chunk bytes; CAN: frame data bytes)."""
    units_duplicated: int = 0
    units_delayed: int = 0
    bytes_corrupted: int = 0
    corrupted_units: int = 0
    """Frames (CAN) or chunks (serial) with at least one corrupted byte."""
    dropped_frames: list[Any] = field(default_factory=list)
    """CAN only: the frames dropped (so a test can count what they carried)."""
    damaged_units: list[int] = field(default_factory=list)
    """Indices (0-based, in the order seen) of the units dropped or corrupted."""


class FaultyTransport(WrappedTransport[Any]):
    """``inner`` with seeded faults injected on :meth:`recv` (and :meth:`send` if asked).

    ``keep_clean``: keep every payload as it was before the faults in :attr:`clean` (bytes
    or CAN frames), so what was lost can be counted against what was sent.
    """

    def __init__(self, inner: Transport[Any], params: FaultParams,
                 on_send: bool = False, on_recv: bool = True, keep_clean: bool = False) -> None:
        super().__init__(inner)
        self.params = params
        self.on_send = on_send
        self.on_recv = on_recv
        self.injected = InjectedFaults()
        self._rng = np.random.default_rng(params.seed)
        self._held: deque[tuple[float, Any]] = deque()
        self._partial = b""
        self.keep_clean = keep_clean
        self.clean: list[Any] = []
        """Payloads before the faults (when ``keep_clean``)."""

    @property
    def name(self) -> str:
        return f"faulty({self.inner.name})"

    @property
    def held_units(self) -> int:
        """Units delayed and not yet passed on (at the end of a run: delayed beyond it)."""
        return len(self._held)

    # -- faults -------------------------------------------------------------------------
    def _corrupt(self, data: bytes, keep_last: bool = False) -> bytes:
        p = self.params.corrupt_byte_p
        if p <= 0 or not data:
            return data
        hit = self._rng.random(len(data)) < p
        if keep_last:
            hit[-1] = False
        if not hit.any():
            return data
        arr = np.frombuffer(data, dtype=np.uint8).copy()
        masks = self._rng.integers(1, 256, size=int(hit.sum()), dtype=np.uint8)
        arr[hit] ^= masks
        self.injected.bytes_corrupted += int(hit.sum())
        self.injected.corrupted_units += 1
        self.injected.damaged_units.append(self.injected.units_seen - 1)
        return arr.tobytes()

    @property
    def _packets(self) -> bool:
        return self.kind != "can" and self.params.serial_unit == "packet"

    def _units(self, payload: Any) -> list[Any]:
        if self.kind == "can":
            return list(payload)
        if not self._packets:
            return [payload] if payload else []
        data = self._partial + bytes(payload)
        end = data.rfind(b"\x00") + 1
        self._partial = data[end:]
        return [part + b"\x00" for part in data[:end].split(b"\x00")[:-1]]

    def _join(self, units: list[Any]) -> Any:
        return units if self.kind == "can" else b"".join(units)

    def _apply(self, payload: Any) -> Any:
        p = self.params
        now = time.monotonic()
        out: list[Any] = []
        for unit in self._units(payload):
            self.injected.units_seen += 1
            if self._rng.random() < p.drop_p:
                self.injected.units_dropped += 1
                self.injected.damaged_units.append(self.injected.units_seen - 1)
                self.injected.bytes_dropped += len(unit.data if self.kind == "can" else unit)
                if self.kind == "can":
                    self.injected.dropped_frames.append(unit)
                continue
            if self.kind == "can":
                data = self._corrupt(bytes(unit.data))
                if data != bytes(unit.data):
                    unit = replace(unit, data=data)
            else:
                unit = self._corrupt(bytes(unit), keep_last=self._packets)
            copies = 1
            if self._rng.random() < p.duplicate_p:
                self.injected.units_duplicated += 1
                copies = 2
            due = now
            if p.delay_p > 0 and self._rng.random() < p.delay_p:
                self.injected.units_delayed += 1
                due = now + p.delay_s
            for _ in range(copies):
                self._held.append((max(due, self._held[-1][0]) if self._held else due, unit))
        while self._held and self._held[0][0] <= now:
            out.append(self._held.popleft()[1])
        return self._join(out)

    # -- Transport ----------------------------------------------------------------------
    def send(self, payload: Any, timeout: float | None = None) -> int:
        if not self.on_send:
            return self.inner.send(payload, timeout)
        n = len(payload)
        self.inner.send(self._apply(payload), timeout)
        return n

    def recv(self, timeout: float | None = None) -> Any:
        payload = self.inner.recv(timeout)
        if not self.on_recv:
            return payload
        if self.keep_clean and payload:
            self.clean.append(list(payload) if self.kind == "can" else bytes(payload))
        return self._apply(payload)

