"""The command line's parser: every subcommand registered, and argparse's errors as one
``skinhil: error:`` line with exit status 2 (:class:`ArgumentParser`)."""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import TYPE_CHECKING, NoReturn

from skinhil.cli.conventions import ERROR_STATUS, finish_parser

if TYPE_CHECKING:
    from skinhil.config import UserConfig

SUBCOMMANDS: tuple[str, ...] = (
    "demo",
    "serve",
    "listen",
    "train",
    "simulate",
    "reproduce",
    "dbc",
    "stimuli",
    "pty",
    "compile",
    "bench",
    "suites",
    "dataset",
    "completion",
)



def error_line(what: str) -> str:
    """The one line every refusal prints: ``skinhil: error: <what — what to do>``."""
    return f"skinhil: error: {what}"


class ArgumentParser(argparse.ArgumentParser):
    """argparse with skinhil's error path: a bad option is one ``skinhil: error:`` line
    saying where to read the usage, exit status 2, no usage block."""

    def error(self, message: str) -> NoReturn:
        print(error_line(f"{message} — see '{self.prog} --help'"), file=sys.stderr)
        sys.exit(ERROR_STATUS)


def version_text() -> str:
    """``skinhil --version``'s line: the package's version and the wire protocol versions
    its board sends and its receiver reads (SPEC.md, "Versions")."""
    from protocols.constants import KNOWN_VERSIONS
    from skinhil import __version__

    return (f"skinhil {__version__} (wire protocol versions "
            f"{', '.join(str(v) for v in KNOWN_VERSIONS)})")


class VersionAction(argparse.Action):
    """``--version``: :func:`version_text` on stdout, exit status 0 (what it imports is
    imported only then)."""

    def __init__(self, option_strings: list[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str | None = None) -> None:
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> NoReturn:
        print(version_text(), flush=True)
        parser.exit()


def build_parser(only: str | None = None, config: UserConfig | None = None
                 ) -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand registered, or only ``only``
    when it names one; every parser given the shared options and epilog
    (:mod:`skinhil.cli.conventions`), and ``config``'s defaults made known to them
    (:mod:`skinhil.cli.user_config`; None: no configuration looked for). Each subcommand
    module imports what it runs on: a board start need not pay for scikit-learn's import;
    a word ``only`` that names none is refused by argparse from the subcommands' names
    alone, no module imported (tests/test_cold_start.py checks it)."""
    parser = ArgumentParser(
        prog="skinhil",
        description="Real-time neuromorphic hardware-in-the-loop emulator of touch.")
    parser.add_argument("--version", action=VersionAction,
                        help="print skinhil's version and the wire versions it reads, and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=ArgumentParser)
    sub.required = True
    if only is not None and only not in SUBCOMMANDS:  # "invalid choice", from the names
        for name in SUBCOMMANDS:
            sub.add_parser(name)
        return parser
    for name in (only,) if only in SUBCOMMANDS else SUBCOMMANDS:
        try:
            module = importlib.import_module(f"skinhil.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"skinhil.cli.{name}":
                continue
            raise
        module.add_parser(sub)
    _finish(parser, sub, config)
    return parser


def _finish(parser: argparse.ArgumentParser, sub: argparse._SubParsersAction,
            config: UserConfig | None) -> None:
    line = None if config is None else config.describe()
    finish_parser(parser, line, top=True)
    for child in sub.choices.values():
        finish_parser(child, line)
    if config is not None:
        from skinhil.cli.user_config import prepare_parser

        prepare_parser(parser, config)
