"""Link URLs: ``SCHEME:TARGET?KEY=VALUE&...`` parsed and written back (docs/links.md).

The scheme names a registered link class (:mod:`skinhil.transports.registry`); the target
and the options are that class's to read (:meth:`Transport.from_url`). Options a class does
not read are refused by :meth:`LinkUrl.check_options`, so a misspelt key never goes unseen.
"""

from __future__ import annotations

import re
import urllib.parse
from dataclasses import dataclass, field

from skinhil.errors import TransportError

SCHEME_PATTERN = re.compile(r"^[a-z][a-z0-9+.-]*$")
"""What a link scheme may be: a lowercase letter, then letters, digits, ``+``, ``.``, ``-``."""
TRUE_WORDS = ("1", "true", "yes", "on")
"""Option values read as true."""
FALSE_WORDS = ("0", "false", "no", "off")
"""Option values read as false."""


@dataclass(frozen=True)
class LinkUrl:
    """A parsed link URL: ``scheme``, ``target`` (a device, channel or address; may be
    empty) and ``options`` (the query's keys and values, in order)."""

    scheme: str
    target: str = ""
    options: dict[str, str] = field(default_factory=dict)

    @classmethod
    def parse(cls, text: str) -> LinkUrl:
        """Parse ``text``; :class:`TransportError` naming the form to give when it is not a
        link URL."""
        scheme, sep, rest = str(text).partition(":")
        if not sep or not SCHEME_PATTERN.match(scheme):
            raise TransportError(f"{text!r} is not a link URL: give SCHEME:TARGET, e.g. "
                                 "serial:/dev/ttyUSB0, can:vcan0, udp:127.0.0.1:9000 or pty:")
        target, _, query = rest.partition("?")
        options: dict[str, str] = {}
        for key, value in urllib.parse.parse_qsl(query, keep_blank_values=True):
            if key in options:
                raise TransportError(f"link URL {text!r} gives option {key!r} twice: give it "
                                     "once")
            options[key] = value
        return cls(scheme, target, options)

    def __str__(self) -> str:
        query = urllib.parse.urlencode(self.options, safe="/:")
        return f"{self.scheme}:{self.target}" + (f"?{query}" if query else "")

    def check_options(self, known: tuple[str, ...]) -> None:
        """:class:`TransportError` when an option is not one of ``known``."""
        for key in self.options:
            if key not in known:
                allowed = ", ".join(known) if known else "none"
                raise TransportError(f"link URL {self} has unknown option {key!r}: give "
                                     f"only what a {self.scheme}: link takes ({allowed})")

    def int_option(self, key: str, default: int | None) -> int | None:
        """Option ``key`` as an integer (``default`` when absent)."""
        text = self.options.get(key)
        if text is None:
            return default
        try:
            return int(text.replace("_", ""))
        except ValueError:
            raise TransportError(f"link URL {self}: {key}={text!r} is not an integer: give "
                                 f"e.g. {key}=1000000") from None

    def bool_option(self, key: str, default: bool = False) -> bool:
        """Option ``key`` as a flag: 1/true/yes/on or 0/false/no/off (``default`` when
        absent)."""
        text = self.options.get(key)
        if text is None:
            return default
        if text.lower() in TRUE_WORDS:
            return True
        if text.lower() in FALSE_WORDS:
            return False
        raise TransportError(f"link URL {self}: {key}={text!r} is not a flag: give {key}=1 "
                             f"or {key}=0")

    def require_target(self, example: str) -> str:
        """The target, or :class:`TransportError` showing ``example`` when it is empty."""
        if not self.target:
            raise TransportError(f"link URL {self} names no target: give e.g. {example}")
        return self.target


def format_url(scheme: str, target: str = "", **options: object) -> str:
    """The URL text of ``scheme``, ``target`` and the ``options`` that are not None
    (flags written 1 or 0)."""
    text = {k: str(int(v)) if isinstance(v, bool) else str(v)
            for k, v in options.items() if v is not None}
    return str(LinkUrl(scheme, target, text))
