"""No output of a command overwrites one of its inputs or another of its outputs.

Every file option of every subcommand is named here as an input (read) or an output
(written); :func:`check_distinct_paths` compares each output with every input and every other
output given on the command line (the same file by another spelling or through a link
included) and refuses a collision before anything is read or written: ``serve --score``
naming the schedule being played would overwrite it with the score, ``listen --model m.npz
--record m.npz`` would overwrite the decoder with the session.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from skinhil.errors import ConfigError

INPUT_OPTIONS: tuple[str, ...] = ("schedule", "replay", "model", "oracle_truth")
"""``args`` attributes of files a command reads (``--schedule``, ``--replay``, ``--model``,
``--oracle-truth``)."""
OUTPUT_OPTIONS: tuple[str, ...] = ("out", "record", "score", "truth", "grasp_truth", "nwb")
"""``args`` attributes of files a command writes."""


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist yet: compare where they would be
        return a.expanduser().resolve() == b.expanduser().resolve()


def check_distinct_paths(args: argparse.Namespace) -> None:
    """Raise :class:`ConfigError` if an output option of ``args`` names the same file as an
    input option or another output option."""
    given = [(name, Path(value), name in OUTPUT_OPTIONS)
             for name in (*INPUT_OPTIONS, *OUTPUT_OPTIONS)
             if isinstance(value := getattr(args, name, None), (str, Path))]
    for i, (name, path, written) in enumerate(given):
        for other, other_path, other_written in given[i + 1:]:
            if (written or other_written) and _same(path, other_path):
                out, inp = (name, other) if written else (other, name)
                what = "is also" if other_written and written else "would overwrite"
                raise ConfigError(f"--{out} '{path}' {what} --{inp} '{other_path}' — give "
                                  f"--{out} a file of its own")
