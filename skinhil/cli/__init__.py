"""The ``skinhil`` command line: one module per subcommand, one error path for all.

Each subcommand module exposes ``add_parser(subparsers)`` (a parser named like the module)
and ``run(args) -> int``. Errors
raised on purpose (:class:`skinhil.errors.SkinhilError`) become one line on stderr and exit
status 2; Ctrl-C becomes exit status 130.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from skinhil.errors import SkinhilError

SUBCOMMANDS: tuple[str, ...] = (
    "demo",
    "serve",
    "listen",
    "train",
    "simulate",
    "reproduce",
    "dbc",
)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand registered, or only ``only``
    when it names one (each subcommand module imports what it runs on: a board start need
    not pay for scikit-learn's import)."""
    parser = argparse.ArgumentParser(
        prog="skinhil",
        description="Real-time neuromorphic hardware-in-the-loop emulator of touch.",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
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
    """Run the command line; returns the process exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in argv if not a.startswith("-")), None)  # -v is the only option
    args = build_parser(command).parse_args(argv)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    try:
        module = importlib.import_module(f"skinhil.cli.{args.command}")
        return int(module.run(args) or 0)
    except SkinhilError as exc:
        print(f"skinhil: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skinhil: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
