"""Two linked pty devices: what ``socat -d -d pty,raw,echo=0 pty,raw,echo=0`` gives, for
machines without socat (``skinhil pty``).

Each side is a pty pair whose slave path a program opens as a serial port (``skinhil serve
--port A``, a decoder under test on ``B``); the bridge copies the bytes each program writes
to the other, unchanged and in order. It keeps both slaves open itself, so a program may
close its end and open it again (a restarted decoder) without breaking the link; while one
side's program is not reading, the bridge stops reading the other side once
:data:`MAX_PENDING` bytes wait (a serial line's flow control: nothing is dropped).
"""

from __future__ import annotations

import logging
import os
import select
import threading
import tty

from skinhil.errors import TransportError

log = logging.getLogger(__name__)

MAX_PENDING = 1 << 16
"""Bytes (per direction) the bridge holds for a side that does not read, before it stops
reading the other side."""
POLL_S = 0.05
"""Longest wait (s) of one pass of the copy loop (how soon a stop request is seen)."""


class PtyBridge:
    """Two pty pairs joined back to back: :attr:`paths` are the two device paths."""

    def __init__(self) -> None:
        self._fds: list[tuple[int, int]] = []
        try:
            for _ in range(2):
                master, slave = os.openpty()
                self._fds.append((master, slave))
                tty.setraw(master)
                tty.setraw(slave)
                os.set_blocking(master, False)
        except OSError as exc:
            self.close()
            raise TransportError(f"cannot make a pty pair: {exc}") from None
        self.paths: tuple[str, str] = (os.ttyname(self._fds[0][1]), os.ttyname(self._fds[1][1]))
        """The device paths of the two ends (``/dev/pts/N``)."""
        self.bytes_copied = [0, 0]
        """Bytes copied from end 0 to end 1, and from end 1 to end 0."""

    def run(self, stop: threading.Event) -> None:
        """Copy bytes both ways until ``stop`` is set."""
        masters = [m for m, _ in self._fds]
        pending = [bytearray(), bytearray()]  # pending[i]: bytes waiting to go to end i
        while not stop.is_set():
            readers = [m for i, m in enumerate(masters) if len(pending[1 - i]) < MAX_PENDING]
            writers = [masters[i] for i in range(2) if pending[i]]
            ready_r, ready_w, _ = select.select(readers, writers, [], POLL_S)
            for i, m in enumerate(masters):
                if m in ready_r:
                    try:
                        data = os.read(m, MAX_PENDING)
                    except (BlockingIOError, InterruptedError):
                        data = b""
                    pending[1 - i] += data
                    self.bytes_copied[i] += len(data)
            for i, m in enumerate(masters):
                if m in ready_w and pending[i]:
                    try:
                        n = os.write(m, pending[i])
                    except (BlockingIOError, InterruptedError):
                        n = 0
                    del pending[i][:n]

    def close(self) -> None:
        """Close both pty pairs (their paths disappear)."""
        for pair in self._fds:
            for fd in pair:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._fds = []

    def __enter__(self) -> PtyBridge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
