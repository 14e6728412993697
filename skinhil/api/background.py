"""What :class:`skinhil.Board` and :class:`skinhil.Receiver` share: a run on a thread of
its own over a link, stopped and closed once, its exception raised in the caller."""

from __future__ import annotations

import threading
from types import TracebackType
from typing import Any, Self

from skinhil.transports import Transport


class BackgroundRun:
    """A run on :attr:`_thread` over :attr:`transport` until :attr:`_stop` is set; the
    thread keeps its exception in :attr:`_error`. ``stop_timeout_s``: the longest
    :meth:`close` waits for the thread (s)."""

    stop_timeout_s: float
    transport: Transport[Any]
    _stop: threading.Event
    _thread: threading.Thread
    _error: BaseException | None

    def close(self) -> None:
        """Stop the run, wait for its thread and close the link; an exception of the thread
        is raised here. Closing twice is a no-op."""
        self._stop.set()
        self._thread.join(self.stop_timeout_s)
        self.transport.shutdown()
        self._raise()

    def _raise(self) -> None:
        error, self._error = self._error, None
        if error is not None:
            raise error

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
