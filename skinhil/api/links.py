"""How the notebook API names a link: a link URL (``serial:/dev/ttyUSB0?baud=921600``,
``can:vcan0``, ``udp:127.0.0.1:9000``, ``pty:``; docs/links.md) or a serial device path."""

from __future__ import annotations

from typing import Any

from skinhil.transports import Role, Transport, format_url, open_link


def link_url(link: str) -> str:
    """``link`` as a link URL: a device path (``/dev/ttyUSB0``, ``/dev/pts/3``) is
    ``serial:PATH``; anything else is taken as a URL."""
    return format_url("serial", link) if link.startswith("/") else link


def open_api_link(link: str | Transport[Any], role: Role) -> Transport[Any]:
    """An open link: ``link`` itself when it is a :class:`Transport`, else the link its URL
    or device path names, opened for ``role``."""
    if isinstance(link, Transport):
        return link
    return open_link(link_url(link), role)
