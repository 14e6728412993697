"""Sphinx directive ``skinhil-cli``: the command-line reference, generated from the argparse
parsers of :func:`skinhil.cli.parser.build_parser` at build time, so it is never stale.

Each subcommand becomes a section: its usage line, its description and every option of every
argument group with its help text (defaults expanded as ``--help`` prints them), then its
epilog (the exit-code table) as written."""

from __future__ import annotations

import argparse

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    if not action.help or action.help == argparse.SUPPRESS:
        return ""
    return parser._get_formatter()._expand_help(action)


def _invocation(action: argparse.Action) -> str:
    if not action.option_strings:
        return action.metavar if isinstance(action.metavar, str) else action.dest.upper()
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    metavar = action.metavar if isinstance(action.metavar, str) else action.dest.upper()
    if action.nargs == "?":
        metavar = f"[{metavar}]"
    return ", ".join(f"{o} {metavar}" for o in action.option_strings)


def _parser_nodes(name: str, parser: argparse.ArgumentParser) -> nodes.section:
    section = nodes.section(ids=[nodes.make_id(f"cli-{name}")])
    section += nodes.title(text=name)
    usage = parser.format_usage().strip()
    section += nodes.literal_block(usage, usage)
    if parser.description:
        for para in parser.description.split("\n\n"):
            section += nodes.paragraph(text=" ".join(para.split()))
    for group in parser._action_groups:
        actions = [a for a in group._group_actions
                   if a.help != argparse.SUPPRESS
                   and not isinstance(a, argparse._SubParsersAction | argparse._HelpAction)]
        if not actions:
            continue
        section += nodes.rubric(text=group.title or "options")
        if group.description:
            section += nodes.paragraph(text=" ".join(group.description.split()))
        items = nodes.definition_list()
        for action in actions:
            item = nodes.definition_list_item()
            term = nodes.term()
            term += nodes.literal(text=_invocation(action))
            item += term
            definition = nodes.definition()
            definition += nodes.paragraph(text=" ".join(_help(parser, action).split()))
            item += definition
            items += item
        section += items
    if parser.epilog:
        epilog = parser.epilog.strip()
        section += nodes.literal_block(epilog, epilog)
    return section


class CliReference(Directive):
    """``.. skinhil-cli::``: every subcommand of ``skinhil``, from the parser."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from skinhil.cli.parser import build_parser

        parser = build_parser()
        out: list[nodes.Node] = [_parser_nodes("skinhil", parser)]
        for name, sub in _subparsers(parser).items():
            out.append(_parser_nodes(f"skinhil {name}", sub))
        return out


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("skinhil-cli", CliReference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
