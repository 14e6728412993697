"""``skinhil completion bash|zsh``: the shell completion script, generated from the parsers
by shtab (the ``completion`` extra)."""

from __future__ import annotations

import argparse

from skinhil.errors import ConfigError

SHELLS = ("bash", "zsh")
"""Shells a completion script is written for."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "completion", help="print the shell completion script (bash or zsh)",
        description="Print the completion script of every skinhil command and option for "
                    "SHELL, generated from the parsers by shtab (pip install "
                    "'skinhil[completion]'). Bash: skinhil completion bash > "
                    "~/.local/share/bash-completion/completions/skinhil; zsh: skinhil "
                    "completion zsh > a folder of your fpath, named _skinhil.")
    p.add_argument("shell", choices=SHELLS, metavar="SHELL", help="bash or zsh")


def run(args: argparse.Namespace) -> int:
    try:
        import shtab
    except ImportError:
        raise ConfigError("shell completion needs shtab — pip install 'skinhil[completion]'"
                          ) from None
    from skinhil.cli.parser import build_parser

    print(shtab.complete(build_parser(), shell=args.shell), end="")
    return 0
