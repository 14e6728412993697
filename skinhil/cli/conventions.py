"""The options and help every subcommand shares, added by :func:`skinhil.cli.parser.build_parser`
to the top-level parser and to each subcommand's, so ``skinhil -v demo`` and ``skinhil demo
-v`` mean the same: ``-v/--verbose``, ``-q/--quiet`` (one meaning everywhere: :data:`QUIET_HELP`;
it implies ``--no-progress`` where a command has that), and the help's epilog: the exit-code
table (:data:`EXIT_CODES`, docs: Command-line conventions) and the configuration file in force.
"""

from __future__ import annotations

import argparse
import json
import math

ERROR_STATUS = 2
"""Exit status of every refusal (bad option, bad file, unusable port, ...)."""

VERBOSE_HELP = "more log output (twice: debug)"
"""``-v/--verbose``'s help, the same on every command."""
QUIET_HELP = ("less output: no progress bars, live lines or notices (and no log warnings); "
              "errors still print")
"""``-q/--quiet``'s help, the same on every command: what it turns off."""
NO_PROGRESS_HELP = "no progress bar"
"""``--no-progress``'s help, the same on every command that has one (``-q`` implies it)."""
MODEL_HELP = ("decoder file written by skinhil train (default: the demo's 6x6 decoder, "
              "trained on first use and cached)")
"""``--model``'s help, the same on every command that decodes (demo, listen, bench): each
falls back to the cached demo decoder."""
JSON_HELP = "one JSON object on stdout: the result, instead of the text"
"""``--json``'s help on every command that prints one result (serve and listen print lines)."""
EXIT_CODES: tuple[tuple[int, str], ...] = (
    (0, "done"),
    (1, "failed: a case did not pass (bench), or stdout could not be written"),
    (ERROR_STATUS, "refused: bad option, file, configuration or link ('skinhil: error:')"),
    (129, "stopped by SIGHUP"),
    (130, "stopped by SIGINT (Ctrl-C), after a clean stop"),
    (143, "stopped by SIGTERM, after a clean stop"),
)
"""Every exit status of every command, with its meaning."""


def add_common_options(parser: argparse.ArgumentParser, top: bool = False) -> None:
    """Add ``-v/--verbose`` and ``-q/--quiet`` to ``parser``; on a subcommand's parser
    (``top`` false) their defaults are left to the top-level parser's, so an option given
    before the command is not undone after it."""
    default: object = argparse.SUPPRESS
    group = parser.add_argument_group("common options (every command)")
    group.add_argument("-v", "--verbose", action="count", default=0 if top else default,
                        help=VERBOSE_HELP)
    group.add_argument("-q", "--quiet", action="store_true",
                        default=False if top else default, help=QUIET_HELP)


def settle_common(args: argparse.Namespace) -> None:
    """What the shared options imply once parsed: ``-q`` turns a command's ``--no-progress``
    on."""
    if args.quiet and hasattr(args, "no_progress"):
        args.no_progress = True


def add_json_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add ``--json`` (:data:`JSON_HELP`) to a command that prints one result."""
    parser.add_argument("--json", action="store_true", help=JSON_HELP)


def print_json(result: dict[str, object]) -> None:
    """``result`` as one JSON line on stdout; a non-finite number is written as its text
    (``"inf"``), which strict JSON readers accept."""
    def clean(value: object) -> object:
        if isinstance(value, float) and not math.isfinite(value):
            return str(value)
        if isinstance(value, dict):
            return {str(k): clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        return value

    print(json.dumps(clean(result), allow_nan=False), flush=True)


def exit_code_table() -> str:
    """The exit-code table as the help's epilog shows it (lines kept as written)."""
    rows = "\n".join(f"  {code:<5}{meaning}" for code, meaning in EXIT_CODES)
    return f"exit status:\n{rows}"


class HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, keeping as written the paragraphs of a description or epilog
    whose lines are indented (tables); the others are filled to the width as usual."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        out = []
        for para in text.split("\n\n"):
            lines = para.splitlines()
            if any(line.startswith("  ") for line in lines):
                out.append("\n".join(indent + line for line in lines))
            else:
                out.append(super()._fill_text(para, width, indent))
        return "\n\n".join(out)


def finish_parser(parser: argparse.ArgumentParser, config_line: str | None,
                  top: bool = False) -> None:
    """Give ``parser`` the shared options and the epilog: the exit-code table and
    ``config_line`` (which configuration file was read; None: not looked for)."""
    add_common_options(parser, top)
    parser.formatter_class = HelpFormatter
    parts = [parser.epilog] if parser.epilog else []
    parts.append(exit_code_table())
    if config_line:
        parts.append(config_line)
    parser.epilog = "\n\n".join(parts)
