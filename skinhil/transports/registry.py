"""Links as a registry of URL schemes, as python-can maps interface names to bus classes
(``BACKENDS`` and its ``can.interface`` entry points) and pyserial maps URL schemes to
handlers (``serial_for_url``).

A scheme names a :class:`~skinhil.transports.base.Transport` class. The installed ones come
from the ``skinhil.links`` entry points (``serial``, ``can``, ``udp``, ``pty`` and any a
package adds), each class imported only when its scheme is opened;
:func:`register_link` adds one in the running process. :func:`open_link` opens a URL
(docs/links.md).
"""

from __future__ import annotations

import logging
from importlib.metadata import entry_points
from typing import Any

from skinhil.errors import TransportError
from skinhil.transports.base import Role, Transport
from skinhil.transports.url import SCHEME_PATTERN, LinkUrl

log = logging.getLogger(__name__)

ENTRY_POINT_GROUP = "skinhil.links"
"""The entry-point group a package registers its link classes under (name: the scheme)."""
ROLES: tuple[Role, ...] = ("board", "host")
"""Who opens a link: the board (it sends to an address) or the host (it listens on one)."""

_registered: dict[str, type[Transport[Any]]] = {}


def register_link(scheme: str, cls: type[Transport[Any]]) -> None:
    """Make ``scheme:`` URLs open with ``cls`` in this process (it replaces an entry point
    of the same name)."""
    if not SCHEME_PATTERN.match(scheme):
        raise TransportError(f"link scheme {scheme!r} is not a URL scheme: give lowercase "
                             "letters, digits, '+', '.' or '-', starting with a letter")
    if not (isinstance(cls, type) and issubclass(cls, Transport)):
        raise TransportError(f"cannot register {cls!r} for {scheme}: give a subclass of "
                             "skinhil.transports.Transport")
    _registered[scheme] = cls


def link_schemes() -> list[str]:
    """Every scheme that opens: the entry points' and those registered in this process."""
    return sorted({ep.name for ep in entry_points(group=ENTRY_POINT_GROUP)} | set(_registered))


def link_class(scheme: str) -> type[Transport[Any]]:
    """The class registered for ``scheme``; :class:`TransportError` naming the schemes
    there are when none is."""
    if scheme in _registered:
        return _registered[scheme]
    for ep in entry_points(group=ENTRY_POINT_GROUP, name=scheme):
        try:
            cls = ep.load()
        except (ImportError, AttributeError) as exc:
            raise TransportError(f"the {scheme}: link's module cannot be loaded ({ep.value}: "
                                 f"{exc}): reinstall the package that provides it") from None
        register_link(scheme, cls)
        return _registered[scheme]
    raise TransportError(f"no link has the scheme {scheme!r}: give one of "
                         f"{', '.join(s + ':' for s in link_schemes())}")


def open_link(url: str | LinkUrl, role: Role = "board") -> Transport[Any]:
    """Open the link ``url`` names (``serial:/dev/ttyUSB0?baud=921600``, ``can:vcan0?fd=1``,
    ``udp:127.0.0.1:9000``, ``pty:``, ...) for ``role``: "board" sends to the address,
    "host" listens on it. Raises :class:`TransportError` with what to give instead."""
    if role not in ROLES:
        raise TransportError(f"link role {role!r}: give 'board' or 'host'")
    parsed = url if isinstance(url, LinkUrl) else LinkUrl.parse(url)
    transport = link_class(parsed.scheme).from_url(parsed, role)
    log.debug("opened %s as %s", transport.url, role)
    return transport
