"""One set of conventions across every subcommand, read from the parsers themselves: the
same option name means the same thing, the shared defaults agree (or the command prints its
own), ``-v/-q`` work after the command, one ``--quiet`` and one ``--no-progress``, a decoder
falls back to the cached demo one everywhere, every ``--help`` ends with the exit-code table,
``serve``'s options are grouped; and the shell completion script."""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys

import pytest

from skinhil.cli.conventions import (
    EXIT_CODES,
    JSON_HELP,
    MODEL_HELP,
    NO_PROGRESS_HELP,
    QUIET_HELP,
)
from skinhil.cli.parser import SUBCOMMANDS, build_parser

SAME_THING_EXCEPT: dict[str, str] = {
    "--out": "each command's own output (a file, a folder, a DBC)",
    "--duration": "board time (serve, demo), wall time (listen), simulated time (simulate)",
    "--board-id": "listen decodes several boards: a list",
    "--fd": "dbc: which layout to print, not a link option",
    "--baud": "demo: the baud of its own pty, not a link shorthand's",
    "--seed": "bench: the seed that draws the suite's seeds",
    "--seeds": "bench: how many seeds; dataset: which",
    "--suite": "serve plays one case; bench and dataset run the suite",
    "--schedule": "what each command does with the file (play, train on, simulate, list)",
    "--record": "serve records the wire; listen the decoded session",
    "--udp": "serve sends to the address; listen listens on it",
    "--json": "serve and listen print JSON lines as they run (docs: Process output)",
    "--rest": "train: the rest of the schedule it simulates, as the board's",
}
"""Options whose name several commands share for different things, and why: for every other
name, the dest, type, action, default and help are one."""
SHARED_DEFAULTS: dict[str, object] = {"seed": 0, "snr_db": 10.0}
"""The defaults every command shares (dest: value)."""
DEFAULT_IN_BANNER: dict[tuple[str, str], str] = {
    ("demo", "seed"): "its banner prints the serve command line with --seed",
    ("simulate", "snr_db"): "its result line prints the SNR and the seed",
}
"""A command whose default differs from :data:`SHARED_DEFAULTS`, and where it prints it."""
NO_RESULTS = frozenset({"dbc", "completion"})
"""Commands whose output is the artefact itself (a DBC, a completion script)."""


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


COMMANDS = _commands()


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {o: a for a in parser._actions for o in a.option_strings}


def _signature(action: argparse.Action, full: bool) -> tuple[object, ...]:
    kind = getattr(action.type, "__name__", action.type)
    base = (action.dest, kind, type(action).__name__, action.nargs, action.required)
    return base + ((repr(action.default), action.help) if full else ())


def test_every_subcommand_is_walked() -> None:
    assert sorted(COMMANDS) == sorted(SUBCOMMANDS)


def test_same_name_same_meaning() -> None:
    seen: dict[str, dict[tuple[object, ...], list[str]]] = {}
    for name, parser in COMMANDS.items():
        for option, action in _options(parser).items():
            if option in SAME_THING_EXCEPT or action.dest == "help":
                continue
            full = action.dest not in SHARED_DEFAULTS  # defaults checked below
            seen.setdefault(option, {}).setdefault(_signature(action, full), []).append(name)
    split = {o: list(v.values()) for o, v in seen.items() if len(v) > 1}
    assert split == {}, split  # each: the commands that disagree, in groups


def test_shared_defaults_or_printed() -> None:
    for name, parser in COMMANDS.items():
        for option, dest in (("--seed", "seed"), ("--snr-db", "snr_db")):
            action = _options(parser).get(option)
            if action is None or (name, option) == ("bench", "--seed"):
                continue
            if action.default != SHARED_DEFAULTS[dest]:
                assert (name, dest) in DEFAULT_IN_BANNER, (name, option, action.default)
    assert "(default: 1)" in " ".join(COMMANDS["demo"].format_help().split())
    assert "(default: inf)" in " ".join(COMMANDS["simulate"].format_help().split())


def test_verbose_and_quiet_before_or_after_the_command() -> None:
    parser = build_parser()
    for argv in (["-v", "dbc"], ["dbc", "-v"]):
        assert parser.parse_args(argv).verbose == 1, argv
    for argv in (["-q", "dbc"], ["dbc", "-q"], ["dbc", "--quiet"]):
        assert parser.parse_args(argv).quiet is True, argv
    args = parser.parse_args(["dbc"])
    assert (args.verbose, args.quiet) == (0, False)
    args = parser.parse_args(["-v", "-v", "dbc", "-q"])
    assert (args.verbose, args.quiet) == (2, True)


def test_one_quiet_and_one_no_progress() -> None:
    from skinhil.cli.conventions import settle_common

    for name, parser in COMMANDS.items():
        options = _options(parser)
        assert options["--quiet"].help == QUIET_HELP and options["-q"] is options["--quiet"]
        if "--no-progress" in options:
            assert options["--no-progress"].help == NO_PROGRESS_HELP, name
            args = build_parser(name).parse_args([name, "-q", *_required(name)])
            settle_common(args)
            assert args.no_progress is True, name  # -q means no bar too


def _required(name: str) -> list[str]:
    return {"train": ["--out", "m.npz"], "reproduce": ["--out", "out"],
            "dataset": ["--suite", "s", "--seeds", "1", "--out", "d.h5"]}.get(name, [])


def test_model_falls_back_everywhere() -> None:
    decoding = [n for n, p in COMMANDS.items() if "--model" in _options(p)]
    assert sorted(decoding) == ["bench", "demo", "listen"]
    for name in decoding:
        action = _options(COMMANDS[name])["--model"]
        assert not action.required and action.default is None and action.help == MODEL_HELP


@pytest.mark.parametrize("name", sorted(set(SUBCOMMANDS) - NO_RESULTS))
def test_json_on_every_command_that_prints_results(name: str) -> None:
    action = _options(COMMANDS[name]).get("--json")
    assert action is not None
    assert name in ("serve", "listen") or action.help == JSON_HELP, name


def test_pty_json_names_both_ends() -> None:
    import json
    import os
    import signal

    from tests.harness.serve import RUN_DIR, serve_env

    proc = subprocess.Popen([sys.executable, "-m", "skinhil", "pty", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=serve_env(), cwd=RUN_DIR)
    try:
        assert proc.stdout is not None
        line = json.loads(proc.stdout.readline())
        assert [os.path.exists(p) for p in line["paths"]] == [True, True]
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)


def test_demo_json_is_one_object_on_stdout() -> None:
    """The shortest demo (one lift of the grasp task, no controller: nothing to train): its
    stdout is exactly one JSON object with the board's score; banners went to stderr.
    (``reproduce --json`` is checked in tests/test_reproduce.py's quick run.)"""
    import json

    from tests.harness.serve import RUN_DIR, serve_env

    proc = subprocess.run([sys.executable, "-m", "skinhil", "demo", "--task", "grasp",
                           "--lifts", "1", "--controller", "off", "--json"],
                          capture_output=True, text=True, env=serve_env(), cwd=RUN_DIR,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert proc.stdout.count("\n") == 1 and isinstance(result, dict)
    assert {"task", "lifts", "snr_db", "seed", "controller", "grips", "board_score",
            "wall_s"} <= set(result)
    assert result["task"] == "grasp" and result["grips"] is None
    assert result["board_score"]["grasp"]["lifts"] == 1, result["board_score"]["grasp"]
    assert "board:" in proc.stderr


def test_exit_code_table_in_every_help() -> None:
    for name, parser in [("skinhil", build_parser()), *COMMANDS.items()]:
        text = parser.format_help()
        assert "exit status:" in text, name
        for code, meaning in EXIT_CODES:
            assert f"  {code:<5}{meaning}" in text, (name, code)


def test_serve_options_grouped() -> None:
    serve = COMMANDS["serve"]
    titles = [g.title or "" for g in serve._action_groups]
    for part in ("model", "stimulus and world", "scoring", "link", "outputs"):
        assert any(t.startswith(part) for t in titles), (part, titles)
    loose = [a.option_strings for g in serve._action_groups if g.title == "options"
             for a in g._group_actions if a.dest != "help"]
    assert loose == []


@pytest.mark.skipif(shutil.which("bash") is None, reason="no bash to check the script")
def test_bash_completion_script() -> None:
    pytest.importorskip("shtab")
    from tests.harness.serve import RUN_DIR, serve_env

    def completion(shell: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "skinhil", "completion", shell],
                              capture_output=True, text=True, timeout=60, env=serve_env(),
                              cwd=RUN_DIR)

    done = completion("bash")
    assert done.returncode == 0, done.stderr
    script = done.stdout
    for word in ("serve", "listen", "--snr-db", "--bus-kwargs"):
        assert word in script, word
    check = subprocess.run(["bash", "-n"], input=script, capture_output=True, text=True,
                           timeout=60)
    assert check.returncode == 0, check.stderr
    zsh = completion("zsh")
    assert zsh.returncode == 0 and zsh.stdout.startswith("#compdef skinhil")
