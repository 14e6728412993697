"""A receive socket's buffer: ask the kernel for room, check what it granted, say when short.

A receiver that reads a fast link (a CAN bus with several boards, a UDP port) in a busy
process needs the kernel to queue frames while it is not scheduled; the kernel grants at
most ``net.core.rmem_max`` (Linux doubles the value asked for its bookkeeping and reports
the doubled figure). A short buffer loses frames under load with no other sign, so the
transport records what it asked and what it got and logs a warning naming the setting.
"""

from __future__ import annotations

import logging
import socket
import sys

log = logging.getLogger(__name__)

RMEM_MAX_PATH = "/proc/sys/net/core/rmem_max"
"""Linux's ceiling on a socket's receive buffer (bytes), set with ``sysctl``."""


def request_receive_buffer(sock: socket.socket, asked: int, what: str) -> int:
    """Ask for an ``asked``-byte receive buffer on ``sock``; return the bytes granted (the
    usable size: Linux reports twice what it grants), logging a warning when it is less."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, asked)
        raw = sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
    except OSError as exc:
        log.warning("%s: cannot set the receive buffer (%s): frames may be lost under load",
                    what, exc)
        return 0
    granted = raw // 2 if sys.platform.startswith("linux") else raw
    if granted < asked:
        log.warning("%s: receive buffer %d bytes granted of %d asked: frames may be lost "
                    "when this process is starved; raise the limit with "
                    "`sysctl -w net.core.rmem_max=%d` (as root)", what, granted, asked, asked)
    return granted
