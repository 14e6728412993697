"""Shared test set-up: the ``vcan`` marker's routing and a real pty pair.

Tests marked ``@pytest.mark.vcan`` need a real ``vcan0``. Where this host has one they run
here; where it has none they are skipped here and run, all of them, inside user-mode Linux
by ``tests/test_transport_vcan_uml.py``, which fails if any of them fails there.
"""

from __future__ import annotations

import os
import threading
import time
import tty
from collections.abc import Iterator

import pytest
from uml_vcan import host_has_can, in_uml

HAS_VCAN = host_has_can("vcan0")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if HAS_VCAN:
        return
    why = ("no vcan0 on this host: run inside user-mode Linux by "
           "tests/test_transport_vcan_uml.py" if not in_uml() else "vcan0 missing inside UML")
    for item in items:
        if "vcan" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=why))


class PtyReader:
    """Reads a pty master on a thread into ``data`` (bytes), so the writer never blocks."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self._buf = bytearray()
        self._lock = threading.Lock()
        self.closed = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        import select

        while not self.closed.is_set():
            try:
                ready, _, _ = select.select([self.fd], [], [], 0.05)
                if not ready:
                    continue
                chunk = os.read(self.fd, 65536)
            except OSError:  # EIO while no slave is open: keep waiting
                time.sleep(0.01)
                continue
            if chunk:
                with self._lock:
                    self._buf += chunk

    def take(self) -> bytes:
        """Everything read since the last call."""
        with self._lock:
            out = bytes(self._buf)
            self._buf.clear()
        return out

    def stop(self) -> None:
        self.closed.set()
        self._thread.join(timeout=1.0)


class PtyPair:
    """A real pty: ``path`` is the slave a program opens by path, ``master`` our end (raw)."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    def close(self) -> None:
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


@pytest.fixture
def pty_pair() -> Iterator[PtyPair]:
    """A raw-mode pty pair, closed after the test."""
    pair = PtyPair()
    yield pair
    pair.close()
