"""The ``skinhil`` command line: one module per subcommand, one error path for all.

Each subcommand module exposes ``add_parser(subparsers)`` (a parser named like the module)
and ``run(args) -> int``. Every refusal, argparse's own included, is one line on stderr,
``skinhil: error: <what> — <what to do>``, and exit status 2: errors raised on purpose
(:class:`skinhil.errors.SkinhilError`) and bad options (:class:`ArgumentParser`). SIGINT,
SIGTERM and SIGHUP are handled from the first instruction of :func:`main` on
(:mod:`skinhil.cli.signals`): exit status 130, 143 or 129, child processes ended, no
traceback.

This module imports nothing at its top but :mod:`skinhil.cli.signals` (standard library
only), so that the signal handlers are in place before anything else is imported: the parser
(:mod:`skinhil.cli.parser`), numpy, numba and the model.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from skinhil.cli import signals


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line (``argv``: the arguments, default ``sys.argv[1:]``); returns the
    process exit status (0, 2 for a refusal, 130/143/129 when stopped by SIGINT/SIGTERM/SIGHUP)."""
    previous = signals.install()
    try:
        if sys.stdout is None:  # started with stdout closed (1>&-): its output would vanish
            print("skinhil: error: standard output is closed — run it with stdout open "
                  "(redirect it to /dev/null to discard it)", file=sys.stderr)
            return 2
        status = _run(list(sys.argv[1:] if argv is None else argv))
        sys.stdout.flush()
        return status
    except OSError as exc:  # stdout on a full device or a closed pipe
        if exc.errno not in _STDOUT_ERRNOS or exc.filename is not None:
            raise
        _stdout_to_devnull()  # what is still buffered goes nowhere, even at exit
        print(f"skinhil: error: cannot write the output: {exc.strerror} — free some space "
              "or redirect stdout elsewhere", file=sys.stderr)
        return 1
    except signals.Stopped as exc:
        signals.end_children()
        print(f"skinhil: stopped by {exc}", file=sys.stderr, flush=True)
        return exc.exit_status
    finally:
        if argv is not None:  # called from Python: the caller's handlers back; as a
            signals.restore(previous)  # program, they stay until the interpreter is gone,
        else:  # recording only
            signals.finish()


_STDOUT_ERRNOS = (28, 32, 5)
"""ENOSPC, EPIPE, EIO: errors of writing to stdout that end a command with one line."""


def _stdout_to_devnull() -> None:
    import os

    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, sys.stdout.fileno() if hasattr(sys.stdout, "fileno") else 1)
    os.close(null)


def _run(argv: list[str]) -> int:
    import importlib
    import logging

    from skinhil.cli.conventions import settle_common
    from skinhil.cli.distinct_paths import check_distinct_paths
    from skinhil.cli.parser import ERROR_STATUS, build_parser, error_line
    from skinhil.errors import SkinhilError

    command = next((a for a in argv if not a.startswith("-")), None)  # -v is the only option
    try:
        config = None
        if command is None and "--version" in argv:
            command = ""  # the subcommands' names only: --version imports none of them
        else:
            from skinhil.config import load_user_config

            config = load_user_config()
        args = build_parser(command, config).parse_args(argv)  # imports the subcommand
        signals.resume()  # start-up done: a Ctrl-C during the imports stops here
        if config is not None:
            from skinhil.cli.user_config import apply_config

            apply_config(args, config)
        settle_common(args)
        level = logging.ERROR if args.quiet else logging.WARNING - 10 * min(args.verbose, 2)
        logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
        check_distinct_paths(args)
        module = importlib.import_module(f"skinhil.cli.{args.command}")
        status = int(module.run(args) or 0)
    except SkinhilError as exc:
        print(error_line(str(exc)), file=sys.stderr)
        return ERROR_STATUS
    return signals.exit_status(status)


if __name__ == "__main__":
    sys.exit(main())
