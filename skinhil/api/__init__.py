"""The notebook API: a board and a receiver in a few lines (docs/api.md).

:class:`Board` runs the emulated board in real time on a background thread over a link it
opens (a pty pair by default); :class:`Receiver` reads its stream on another thread, hands
out the events as numpy structured arrays and sends the host's commands back. Both are
context managers; closing one stops its thread and closes its link.
"""

from skinhil.api.board import Board
from skinhil.api.receiver import Receiver

__all__ = ["Board", "Receiver"]
