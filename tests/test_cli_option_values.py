"""Generated bad input: hypothesis draws a value for one option of one subcommand (numbers
of every size and kind, NaN, infinities, text with control characters) and parses it
in-process with the command line's own parser. Whatever the value, the outcome is a parsed
option or one ``skinhil: error:`` line with exit status 2, never another exception (an
OverflowError or ValueError of a type function is a traceback to a user); and for ``serve``
a parsed command line makes a board configuration or one refusal."""

from __future__ import annotations

import argparse
import contextlib
import functools
import io
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skinhil.cli.parser import build_parser
from skinhil.errors import SkinhilError

BASE = {
    "serve": ["--port", "loop://"],
    "listen": ["--port", "loop://", "--model", "m.npz"],
    "simulate": [],
    "train": ["--out", "m.npz"],
    "demo": [],
    "reproduce": ["--out", "r"],
}
"""Each subcommand's required options, around the option under test."""


def _options(command: str) -> list[str]:
    """The options of ``command`` that take a value checked by a type or choices."""
    sub = build_parser(command)._subparsers._group_actions[0].choices[command]  # type: ignore[union-attr]
    return sorted(opt for action in sub._actions if action.option_strings
                  and action.nargs != 0 and (action.type is not None or action.choices)
                  for opt in action.option_strings if opt.startswith("--"))


OPTIONS = [(command, option) for command in BASE for option in _options(command)]

EDGES = ["nan", "-inf", "inf", "1e308", "-1e308", "1e-320", "0", "-0", "-1", "", " ",
         "0x10", "1_000", "١٢", "9" * 400, "1e999", "3x3", "0x0", "99999x2", "a\nb",
         "\x1b[31m", "127.0.0.1:99999", ",", "0,1,-1", "x" * 100_000]
"""Values every option is given, one by one."""

VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-(10**30), max_value=10**30).map(str),
    st.sampled_from(EDGES),
    st.text(max_size=20))


@functools.cache
def _parser(command: str) -> argparse.ArgumentParser:
    return build_parser(command)


def test_every_option_is_drawn() -> None:
    assert len(OPTIONS) >= 40


def _check(command: str, option: str, value: str) -> None:
    """``value`` for ``option`` parses, or is refused in one line with status 2."""
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr):
            args = _parser(command).parse_args([command, *BASE[command], option, value])
    except SystemExit as exc:
        err = stderr.getvalue()
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert exc.code == 2 and len(lines) == 1 and lines[0].startswith("skinhil: error: "), \
            err
        return
    for name, v in vars(args).items():  # a parsed number is a finite one, or inf on purpose
        if isinstance(v, float) and not math.isfinite(v):
            assert v == math.inf and name in ("snr_db", "speed"), (name, v)
    if command == "serve":
        _serve_config(args)


@pytest.mark.parametrize("command, option", OPTIONS)
def test_every_edge_value_of_every_option(command: str, option: str) -> None:
    for value in EDGES:
        _check(command, option, value)


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(case=st.sampled_from(OPTIONS), value=VALUES)
def test_any_option_value_parses_or_is_refused_in_one_line(case, value) -> None:
    _check(*case, value)


def _serve_config(args: argparse.Namespace) -> None:
    """What serve builds from its options before a link opens: the board's configuration
    and the decoder under test's scoreboard."""
    from skinhil.cli.serve import _config
    from skinhil.scoring import DecisionScoreboard

    for make in (lambda: _config(args), lambda: DecisionScoreboard(args.response_window_s)):
        try:
            make()
        except SkinhilError:
            pass


@pytest.mark.parametrize("value", ["1e308", "nan", "inf", "-1", "0"])
def test_response_window_out_of_range_is_refused(value: str, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        build_parser("serve").parse_args(["serve", "--port", "loop://", "--response-window",
                                          value])
    assert exc.value.code == 2 and "--response-window" in capsys.readouterr().err
