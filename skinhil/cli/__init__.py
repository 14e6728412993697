"""The ``skinhil`` command line: one module per subcommand, one error path for all.

Each subcommand module exposes ``add_parser(subparsers)`` (a parser named like the module)
and ``run(args) -> int``. Every refusal, argparse's own included, is one line on stderr,
``skinhil: error: <what> — <what to do>``, and exit status 2: errors raised on purpose
(:class:`skinhil.errors.SkinhilError`) and bad options (:class:`ArgumentParser`). SIGINT and
SIGTERM are handled from the first instruction of :func:`main` on
(:mod:`skinhil.cli.signals`): exit status 130 or 143, child processes ended, no traceback.

This module imports only the standard library at its top, so that the signal handlers are
in place before numpy, numba and the model are imported.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence
from typing import NoReturn

from skinhil.cli import signals

SUBCOMMANDS: tuple[str, ...] = (
    "demo",
    "serve",
    "listen",
    "train",
    "simulate",
    "reproduce",
    "dbc",
    "compile",
)

ERROR_STATUS = 2
"""Exit status of every refusal (bad option, bad file, unusable port, ...)."""


def error_line(what: str) -> str:
    """The one line every refusal prints: ``skinhil: error: <what — what to do>``."""
    return f"skinhil: error: {what}"


class ArgumentParser(argparse.ArgumentParser):
    """argparse with skinhil's error path: a bad option is one ``skinhil: error:`` line
    saying where to read the usage, exit status 2, no usage block."""

    def error(self, message: str) -> NoReturn:
        print(error_line(f"{message} — see '{self.prog} --help'"), file=sys.stderr)
        sys.exit(ERROR_STATUS)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand registered, or only ``only``
    when it names one (each subcommand module imports what it runs on: a board start need
    not pay for scikit-learn's import)."""
    parser = ArgumentParser(
        prog="skinhil",
        description="Real-time neuromorphic hardware-in-the-loop emulator of touch.")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=ArgumentParser)
    sub.required = True
    for name in (only,) if only in SUBCOMMANDS else SUBCOMMANDS:
        try:
            module = importlib.import_module(f"skinhil.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"skinhil.cli.{name}":
                continue
            raise
        module.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit status (0, 2 for a refusal, 130/143
    when stopped by SIGINT/SIGTERM)."""
    signals.install()
    try:
        return _run(list(sys.argv[1:] if argv is None else argv))
    except signals.Stopped as exc:
        signals.end_children()
        print(f"skinhil: stopped by {exc}", file=sys.stderr, flush=True)
        return exc.exit_status


def _run(argv: list[str]) -> int:
    command = next((a for a in argv if not a.startswith("-")), None)  # -v is the only option
    from skinhil.errors import SkinhilError

    try:
        args = build_parser(command).parse_args(argv)
        level = logging.WARNING - 10 * min(args.verbose, 2)
        logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
        if args.command in KERNEL_COMMANDS:
            from skinhil.cli.compile import announce_cold_cache

            announce_cold_cache(args.command)
        module = importlib.import_module(f"skinhil.cli.{args.command}")
        status = int(module.run(args) or 0)
    except SkinhilError as exc:
        print(error_line(str(exc)), file=sys.stderr)
        return ERROR_STATUS
    return signals.exit_status(status)


KERNEL_COMMANDS: frozenset[str] = frozenset({"serve", "listen", "demo", "train", "simulate"})
"""Subcommands that run the model's or the receiver's compiled kernels: on a cold kernel
cache they say first that they compile, and about how long it takes."""


if __name__ == "__main__":
    sys.exit(main())
