"""The user's configuration file, ``skinhil.toml``: per-user defaults of the command line
(port, baud, CAN channel and interface, decoder file), checked against the ``config`` JSON
Schema (:mod:`skinhil.schemas`). docs: How-to, Configuration.

- :func:`config_paths` — where the file is looked for, first found wins;
- :func:`load_user_config` — the file found, read and checked, as a :class:`UserConfig`.
"""

from skinhil.config.user_file import (
    CONFIG_FILE_NAME,
    LINK_TARGET_KEYS,
    UserConfig,
    config_paths,
    load_user_config,
)

__all__ = ["CONFIG_FILE_NAME", "LINK_TARGET_KEYS", "UserConfig", "config_paths",
           "load_user_config"]
