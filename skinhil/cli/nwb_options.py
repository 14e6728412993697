"""The NWB metadata options of the commands that write NWB files (``simulate --out x.nwb``,
``listen --record x.nwb``): one helper for both."""

from __future__ import annotations

import argparse

from skinhil.errors import ConfigError
from skinhil.nwb.metadata import DEFAULT_KEYWORDS, NwbMetadata

OPTIONS = (("subject_id", "--subject-id"), ("subject_description", "--subject-description"),
           ("experimenter", "--experimenter"), ("institution", "--institution"),
           ("lab", "--lab"), ("experiment_description", "--experiment-description"),
           ("keywords", "--keywords"), ("session_id", "--session-id"))
"""(attribute, option) of every NWB metadata option."""


def _keywords(text: str) -> list[str]:
    words = [w.strip() for w in text.split(",") if w.strip()]
    if not words:
        raise argparse.ArgumentTypeError(f"{text!r}: give keywords such as touch,slip")
    return words


def _text(text: str) -> str:
    if not text.strip():
        raise argparse.ArgumentTypeError("empty: give a text")
    return text.strip()


def add_nwb_args(parser: argparse.ArgumentParser) -> None:
    """Add the NWB metadata options (see :class:`skinhil.nwb.metadata.NwbMetadata`)."""
    g = parser.add_argument_group(
        "NWB metadata", "what an .nwb output says of its session (DANDI and nwbinspector "
        "want them; the defaults describe the simulated skin)")
    g.add_argument("--subject-id", type=_text, metavar="TEXT",
                   help="the subject's id (default: skinhil-skin-ROWSxCOLS)")
    g.add_argument("--subject-description", type=_text, metavar="TEXT",
                   help="the subject's description (default: the simulated skin's model "
                        "and size)")
    g.add_argument("--experimenter", type=_text, action="append", metavar="'LAST, FIRST'",
                   help="who ran the session; repeat for several (default: the login name)")
    g.add_argument("--institution", type=_text, metavar="TEXT",
                   help="the institution (default: none written)")
    g.add_argument("--lab", type=_text, metavar="TEXT", help="the lab (default: none written)")
    g.add_argument("--experiment-description", type=_text, metavar="TEXT",
                   help="what the experiment was (default: what the command did)")
    g.add_argument("--keywords", type=_keywords, metavar="WORD[,WORD...]",
                   help=f"keywords (default: {','.join(DEFAULT_KEYWORDS)})")
    g.add_argument("--session-id", type=_text, metavar="TEXT",
                   help="the session's id (default: skinhil-COMMAND-UTC start time)")


def nwb_metadata(args: argparse.Namespace, writes_nwb: bool) -> NwbMetadata:
    """The metadata the options give; refused (one line) when they are given without an
    .nwb output (``writes_nwb`` False), which would drop them silently."""
    given = [opt for attr, opt in OPTIONS if getattr(args, attr, None) is not None]
    if given and not writes_nwb:
        raise ConfigError(f"{given[0]} describes an NWB file: give an output ending in .nwb "
                          "or drop it")
    return NwbMetadata(
        subject_id=args.subject_id, subject_description=args.subject_description,
        experimenter=tuple(args.experimenter or ()), institution=args.institution,
        lab=args.lab, experiment_description=args.experiment_description,
        keywords=tuple(args.keywords) if args.keywords else DEFAULT_KEYWORDS,
        session_id=args.session_id)
