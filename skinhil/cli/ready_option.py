"""``--ready-fd N`` and where the ready line goes (:mod:`skinhil.process_output`).

``serve`` and ``listen`` say they run with one ready line: on stdout with ``--json``, and to
the inherited file descriptor N with ``--ready-fd N`` (then closed), in any output mode. The
human banner on stderr is for people; a program waits for the ready line.
"""

from __future__ import annotations

import argparse
from typing import Any

from skinhil.cli.values import integer
from skinhil.process_output import check_ready_fd, line, write_ready_fd

MAX_FD = 1 << 20
"""Largest file descriptor ``--ready-fd`` takes (0..2 are the standard streams, refused)."""


def add_ready_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add ``--ready-fd N`` to ``parser`` (or one of its groups)."""
    parser.add_argument("--ready-fd", type=integer(3, MAX_FD, "file descriptor"),
                        metavar="N",
                        help="once the link is open and the run starts, write the ready line "
                             "(one JSON object, docs: Process output) to the inherited "
                             "file descriptor N and close it; with --json it is on stdout "
                             "as well")


def check_ready(args: argparse.Namespace) -> None:
    """Refuse a ``--ready-fd`` that is not open, before any work (:class:`ConfigError`)."""
    check_ready_fd(getattr(args, "ready_fd", None))


def announce_ready(args: argparse.Namespace, record: dict[str, Any]) -> None:
    """Send the ready line ``record`` where ``args`` ask: stdout with ``--json``, the file
    descriptor of ``--ready-fd``."""
    if getattr(args, "json", False):
        print(line(record), flush=True)
    fd = getattr(args, "ready_fd", None)
    if fd is not None:
        write_ready_fd(fd, record)
        args.ready_fd = None  # said once
