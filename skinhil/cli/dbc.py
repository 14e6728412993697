"""``skinhil dbc``: write the CAN database (DBC) of one board id, classic CAN or CAN FD."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from protocols.dbc import dbc_text
from skinhil.errors import ConfigError


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "dbc", help="write the CAN database (DBC) of a board id",
        description="Write the DBC of the CAN layout for one board id, so cantools, SavvyCAN "
                    "and candump users decode every frame the board sends with default "
                    "settings. protocols/skinhil.dbc and skinhil_fd.dbc are board 0's.")
    p.add_argument("--board-id", type=int, default=0, metavar="N",
                   help="board id 0..15, as given to skinhil serve (default: 0)")
    p.add_argument("--fd", action="store_true", help="the CAN FD layout (default: classic)")
    p.add_argument("--out", type=Path, metavar="FILE", help="output file (default: stdout)")


def run(args: argparse.Namespace) -> int:
    if not 0 <= args.board_id <= 15:
        raise ConfigError(f"--board-id {args.board_id}: give a board id from 0 to 15")
    text = dbc_text(args.board_id, args.fd)
    if args.out is None:
        sys.stdout.write(text)
    else:
        try:
            args.out.write_text(text, encoding="ascii")
        except OSError as exc:
            raise ConfigError(f"cannot write {args.out}: {exc.strerror}; choose another "
                              "--out path") from None
        print(f"wrote {args.out} (board {args.board_id}, "
              f"{'CAN FD' if args.fd else 'classic CAN'})")
    return 0
