"""The host side of a link under test: decode what the board sends, send it commands.

A peer reads its end of the link on a thread (a pty master, a CAN bus through
:class:`skinhil.transports.CanTransport`, or a UDP port through
:class:`skinhil.transports.UdpTransport`), feeds the protocols decoder and keeps every
event and record in arrival order.
"""

from __future__ import annotations

import os
import select
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import protocols
from skinhil.events import EVENT_DTYPE
from skinhil.transports import CanTransport, UdpTransport


class Peer:
    """Decoded stream so far: ``events`` (EVENT_DTYPE array), ``records`` (list)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._events: list[np.ndarray] = []
        self._records: list[Any] = []
        self.events_before: list[int] = []
        """For each record, the events decoded in earlier reads (before its read)."""
        self.events_after: list[int] = []
        """For each record, the events decoded up to and including its read."""
        self._n_events = 0
        self.raw_units = 0
        self.arrivals: list[tuple[float, int]] = []
        """(monotonic time, bytes or frames) of every read."""
        self.decoder: Any = None
        self._stop = threading.Event()
        self._token = 0

    def _take(self, res: Any, units: int) -> None:
        with self._lock:
            self.arrivals.append((time.monotonic(), units))
            self.raw_units += units
            for rec in res.records:
                self._records.append(rec)
                self.events_before.append(self._n_events)
                self.events_after.append(self._n_events + len(res.events))
            if len(res.events):
                self._events.append(res.events)
                self._n_events += len(res.events)

    @property
    def events(self) -> np.ndarray:
        with self._lock:
            return np.concatenate(self._events) if self._events else np.zeros(0, EVENT_DTYPE)

    @property
    def records(self) -> list[Any]:
        with self._lock:
            return list(self._records)

    def of(self, cls: type) -> list[Any]:
        return [r for r in self.records if isinstance(r, cls)]

    def wait_for(self, pred: Callable[[Peer], bool], timeout_s: float) -> bool:
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if pred(self):
                return True
            time.sleep(0.01)
        return pred(self)

    def next_token(self) -> int:
        self._token += 1
        return self._token

    def command(self, opcode: Any, arg: float = 0.0) -> int:
        """Send a command; return its token."""
        token = self.next_token()
        self._send_command(protocols.Command(token=token, opcode=opcode, arg=arg))
        return token

    def decision(self, stimulus_id: int, confidence: float | None = None) -> int:
        """Send a DECISION (the decoder under test's answer); return its token."""
        token = self.next_token()
        self._send_command(protocols.Decision(token, stimulus_id, confidence))
        return token

    def _send_command(self, cmd: Any) -> None:
        raise NotImplementedError

    def close(self) -> None:
        self._stop.set()


class PtyPeer(Peer):
    """The host end of a pty (its master fd), decoding the serial protocol."""

    def __init__(self, master_fd: int) -> None:
        super().__init__()
        self.fd = master_fd
        self.decoder = protocols.SerialDecoder()
        self.encoder = protocols.SerialEncoder()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self.fd], [], [], 0.05)
                if not ready:
                    continue
                chunk = os.read(self.fd, 65536)
            except OSError:
                time.sleep(0.01)
                continue
            if chunk:
                self._take(self.decoder.feed(chunk), len(chunk))

    def _send_command(self, cmd: Any) -> None:
        os.write(self.fd, self.encoder.command(cmd))

    def close(self) -> None:
        super().close()
        self._thread.join(timeout=1.0)


class CanPeer(Peer):
    """A second node on a CAN bus, decoding the CAN layout of board ``board_id``."""

    def __init__(self, channel: str = "vcan0", interface: str = "socketcan", fd: bool = False,
                 board_id: int = 0, bitrate: int = 1_000_000) -> None:
        super().__init__()
        self.bus = CanTransport(channel, interface, fd=fd, bitrate=bitrate)
        self.decoder = protocols.CanDecoder(board_id=board_id, fd=fd)
        self.encoder = protocols.CanEncoder(board_id=board_id, fd=fd)
        self.frames: list[protocols.CanFrame] = []
        """Every frame received, as it came."""
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            frames = self.bus.recv(timeout=0.05)
            if frames:
                self.frames.extend(frames)
                self._take(self.decoder.feed(frames), len(frames))

    def _send_command(self, cmd: Any) -> None:
        self.bus.send(self.encoder.command(cmd), timeout=1.0)

    def close(self) -> None:
        super().close()
        self._thread.join(timeout=1.0)
        self.bus.shutdown()


class UdpPeer(Peer):
    """A host listening on a UDP port of 127.0.0.1, decoding the serial protocol (of the
    given ``versions``); commands go to the board heard last. ``datagram_ends`` is the last
    byte of every datagram."""

    def __init__(self, versions: tuple[int, ...] = (3, 4)) -> None:
        super().__init__()
        self.link = UdpTransport("127.0.0.1", 0, listen=True)
        self.port = self.link.port
        self.decoder = protocols.SerialDecoder(versions)
        self.encoder = protocols.SerialEncoder()
        self.datagram_ends: list[int] = []
        self.datagrams: list[bytes] = []
        """Every datagram received, as it came."""
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            for _, data in self.link.recv_from(timeout=0.05):
                self.datagram_ends.append(data[-1])
                self.datagrams.append(data)
                self._take(self.decoder.feed(data), len(data))

    def _send_command(self, cmd: Any) -> None:
        self.link.send(self.encoder.command(cmd), timeout=1.0)

    def close(self) -> None:
        super().close()
        self._thread.join(timeout=1.0)
        self.link.shutdown()
