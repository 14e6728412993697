"""The bench's own serial link: the board on one pty pair, the decoder on another, and a
relay between them that taps the board's stream (and, to check a rig, injects faults).

The relay copies the board's bytes to the decoder and the decoder's bytes (its DECISIONs and
commands) to the board, unchanged and in order, on a thread. It never holds the board back:
what the decoder does not read waits in the relay (up to :data:`MAX_PENDING` bytes, past
which it is dropped and counted). On the way down a :class:`protocols.SerialDecoder` decodes
the stream as the decoder receives it, so the rig counts the frames the link damaged or lost
(:mod:`skinhil.campaign.rig`) whatever the decoder under test makes of them. With
``faults`` (:class:`~skinhil.transports.faults.FaultParams`) the board's side is read
through a :class:`~skinhil.transports.faults.FaultyTransport`: a bad cable, on purpose.
"""

from __future__ import annotations

import os
import select
import threading
from dataclasses import asdict
from typing import Any

from protocols import SerialDecoder
from skinhil.errors import SkinhilError
from skinhil.transports import PtyMasterTransport, Transport
from skinhil.transports.faults import FaultParams, FaultyTransport

MAX_PENDING = 16 << 20
"""Bytes the relay holds for a decoder that does not read, before it drops them."""
POLL_S = 0.05
"""Longest wait (s) of one pass of the relay (how soon a stop is seen)."""


class RelayLink:
    """Two pty pairs and the relay between them: :attr:`board_path` for ``serve --port``,
    :attr:`decoder_path` for the decoder; :meth:`start` / :meth:`stop` run the relay."""

    def __init__(self, baud: int, faults: FaultParams | None = None) -> None:
        self._board, self._board_slave = PtyMasterTransport.open_pair(baud)
        try:
            self._decoder, self._decoder_slave = PtyMasterTransport.open_pair(baud)
        except OSError:
            self._board.shutdown()
            os.close(self._board_slave)
            raise
        self._down: Transport[bytes] = (self._board if faults is None
                                        else FaultyTransport(self._board, faults))
        self.faults = self._down if isinstance(self._down, FaultyTransport) else None
        self.tap = SerialDecoder()
        """Decodes what the decoder receives: its ``counters`` are the link's."""
        self.relay_dropped = 0
        """Bytes dropped because the decoder did not read them."""
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: str | None = None

    @property
    def board_path(self) -> str:
        return self._board.slave_path

    @property
    def decoder_path(self) -> str:
        return self._decoder.slave_path

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="bench-relay", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        down, up = bytearray(), bytearray()
        try:
            while not self._stop.is_set():
                writers = [t.fd for t, q in ((self._decoder, down), (self._board, up)) if q]
                ready, _, _ = select.select([self._board.fd, self._decoder.fd], writers, [],
                                            POLL_S)
                if self._board.fd in ready:
                    data = self._down.recv(0)
                    if data:
                        self.tap.feed(data)
                        down += data
                        if len(down) > MAX_PENDING:
                            self.relay_dropped += len(down) - MAX_PENDING
                            del down[:len(down) - MAX_PENDING]
                if self._decoder.fd in ready:
                    up += self._decoder.recv(0)
                if down:
                    del down[:self._decoder.send(bytes(down), 0)]
                if up:
                    del up[:self._board.send(bytes(up), 0)]
        except SkinhilError as exc:  # a pty gone, or a stream the tap cannot read
            self.error = str(exc)

    def counters(self) -> dict[str, Any]:
        """The tap's link counters, what the relay dropped and the faults injected."""
        out: dict[str, Any] = {**asdict(self.tap.counters), "relay_dropped": self.relay_dropped}
        if self.faults is not None:
            f = self.faults.injected
            out["injected"] = {"units_seen": f.units_seen, "dropped": f.units_dropped,
                               "corrupted": f.corrupted_units, "duplicated": f.units_duplicated,
                               "delayed": f.units_delayed,
                               "held_at_end": self.faults.held_units}
        return out

    def stop(self) -> None:
        """Stop the relay and close both pty pairs."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
        for transport, slave in ((self._board, self._board_slave),
                                 (self._decoder, self._decoder_slave)):
            transport.shutdown()
            try:
                os.close(slave)
            except OSError:
                pass

    def __enter__(self) -> RelayLink:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
