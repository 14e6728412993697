"""Finding, reading and checking ``skinhil.toml``.

Looked for in the working directory, then in ``$XDG_CONFIG_HOME/skinhil/`` (``XDG_CONFIG_HOME``
unset or empty: ``~/.config``); the first found is the one read, the other is not merged.
A file that is not TOML, or that its schema (``skinhil/schemas/config.schema.json``) refuses,
is a :class:`~skinhil.errors.ConfigError` of one line naming the file and the key.
"""

from __future__ import annotations

import logging
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from skinhil.errors import ConfigError

log = logging.getLogger(__name__)

CONFIG_FILE_NAME = "skinhil.toml"
"""The configuration file's name, in each folder looked in."""
LINK_TARGET_KEYS = ("link", "port", "can")
"""Keys that choose the link (at most one), as ``--link``, ``--port`` and ``--can`` do."""
MAX_CONFIG_BYTES = 64 * 1024
"""Largest configuration file read (bytes): a few lines of settings, never data."""


@dataclass(frozen=True)
class UserConfig:
    """The configuration in force: ``path``, the file read (None: none found), ``searched``,
    the paths looked at in order, and ``values``, its checked keys (relative ``model`` paths
    made relative to the file's folder)."""

    path: Path | None = None
    searched: tuple[Path, ...] = ()
    values: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def describe(self) -> str:
        """Which file was read, or where none was found: a heading line, then one indented
        line per path."""
        if self.path is not None:
            return f"configuration (command-line options win):\n  {self.path} (read)"
        return "configuration: none, looked for\n" + "\n".join(f"  {p}" for p in self.searched)


def config_paths(cwd: Path | None = None, environ: Mapping[str, str] | None = None
                 ) -> tuple[Path, ...]:
    """Where ``skinhil.toml`` is looked for, in order: ``cwd`` (default the working
    directory), then ``$XDG_CONFIG_HOME/skinhil`` (default ``~/.config/skinhil``)."""
    env = os.environ if environ is None else environ
    base = env.get("XDG_CONFIG_HOME") or ""
    user = Path(base) if base else Path(env.get("HOME") or Path.home()) / ".config"
    return ((cwd or Path.cwd()) / CONFIG_FILE_NAME, user / "skinhil" / CONFIG_FILE_NAME)


def load_user_config(cwd: Path | None = None, environ: Mapping[str, str] | None = None
                     ) -> UserConfig:
    """The first ``skinhil.toml`` of :func:`config_paths`, read and checked;
    :class:`ConfigError` naming the file (and the key) when it cannot be used."""
    searched = config_paths(cwd, environ)
    for path in searched:
        if path.is_file():
            values = _read(path)
            log.info("read the configuration %s", path)
            return UserConfig(path, searched, MappingProxyType(values))
    return UserConfig(None, searched)


def _read(path: Path) -> dict[str, Any]:
    from skinhil.schemas import validate

    try:
        with path.open("rb") as f:
            data = f.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"cannot read the configuration {path}: {exc.strerror} — fix its "
                          "permissions or remove it") from None
    if len(data) > MAX_CONFIG_BYTES:
        raise ConfigError(f"the configuration {path} is over {MAX_CONFIG_BYTES // 1024} KiB — "
                          "give a few lines of settings (docs: Configuration)")
    try:
        document = tomllib.loads(data.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"the configuration {path} is not TOML: {exc} — fix it or remove "
                          "it") from None
    validate("config", document, where=f"the configuration {path}")
    targets = [k for k in LINK_TARGET_KEYS if k in document]
    if len(targets) > 1:
        raise ConfigError(f"the configuration {path}: keys {' and '.join(targets)} both choose "
                          "the link — keep one")
    if "bus_kwargs" in document:
        from skinhil.transports.can import format_bus_kwargs, parse_bus_kwargs

        try:
            parse_bus_kwargs(format_bus_kwargs(document["bus_kwargs"]))
        except ValueError as exc:
            raise ConfigError(f"the configuration {path}: key bus_kwargs: {exc}") from None
    if "model" in document:
        document["model"] = str(path.parent / Path(document["model"]).expanduser())
    return document
