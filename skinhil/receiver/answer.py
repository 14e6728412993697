"""The reference receiver as a decoder under test: each of its decisions goes back to the
board as a DECISION (``skinhil listen --answer``), so the board scores it with no hardware.

Every decision is answered, false alarms included (the board scores what it gets, as it
would a user's decoder); no confidence is sent (the linear decoder's decision values are not
probabilities). The board's ACKs of these DECISIONs are counted.
"""

from __future__ import annotations

import logging
from typing import Any

import protocols
from skinhil.errors import TransportError
from skinhil.receiver.receiver import Receiver, ReceiverListener
from skinhil.receiver.scoring import ScoredDecision

log = logging.getLogger(__name__)

SEND_TIMEOUT_S = 0.5
"""Longest a DECISION may wait for room on the link (s); one that cannot go is counted."""


def host_encoder(transport: Any, board_id: int) -> Any:
    """The protocols encoder a host uses to send COMMAND units on ``transport``'s link."""
    return transport.codec_pair(board_id=board_id)[0]


class CommandSender(ReceiverListener):
    """Sends COMMAND units to the board on ``transport`` and counts them and their ACKs;
    ``encoder`` another sender's encoder when both send on one link (the host's sequence
    numbers stay one count, SPEC.md §3.5)."""

    def __init__(self, transport: Any, board_id: int, encoder: Any = None) -> None:
        self.transport = transport
        self.encoder = encoder if encoder is not None else host_encoder(transport, board_id)
        self.sent = 0
        """Commands handed to the link."""
        self.unsent = 0
        """Commands the link refused (gone, or no room within :data:`SEND_TIMEOUT_S`)."""
        self.acked = 0
        """Commands the board ACKed."""
        self.nacked = 0
        """Commands the board NACKed."""

    def send(self, record: Any, what: str) -> bool:
        """Encode and send ``record`` (a command), counted; False when the link refused it
        (``what`` names it in the warning)."""
        payload = self.encoder.command(record)
        try:
            done = self.transport.send(payload, timeout=SEND_TIMEOUT_S)
        except TransportError as exc:
            log.warning("%s not sent: %s", what, exc)
            done = -1
        if done < len(payload):  # bytes (serial) or frames (CAN) handed to the link
            log.warning("%s not sent: the link had no room for %g s", what, SEND_TIMEOUT_S)
            self.unsent += 1
            return False
        self.sent += 1
        return True

    def count_ack(self, ack: Any) -> None:
        """Count an ACK of one of these commands."""
        if ack.ok:
            self.acked += 1
        else:
            self.nacked += 1

    def as_dict(self) -> dict[str, int]:
        """The counters: sent, unsent, acked, nacked, and ``unanswered``: sent, with no ACK
        or NACK received (the board never executed them: still queued when its run ended,
        refused for want of room beyond its answer budget, or their ACK lost)."""
        return {"sent": self.sent, "unsent": self.unsent, "acked": self.acked,
                "nacked": self.nacked, "unanswered": self.sent - self.acked - self.nacked}


class DecisionAnswerer(CommandSender):
    """Sends each decision of ``receiver`` to its board as a DECISION (SPEC.md §3.5.1); an
    ACK says it was scored, a NACK that it was counted while stopped or for an unknown id."""

    def __init__(self, receiver: Receiver) -> None:
        super().__init__(receiver.transport, receiver.board_id)
        self.receiver = receiver
        self._token = 0
        self._tokens: set[int] = set()
        self.tokens: list[int | None] = []
        """The DECISION token of each decision, in order (None: not sent); the board's
        scoreboard log names the same tokens."""

    def on_decision(self, decision: ScoredDecision) -> None:
        self._token = (self._token + 1) % 65536
        label = int(decision.prediction.label)
        if not self.send(protocols.Decision(self._token, label),
                         f"DECISION for stimulus {label}"):
            self.tokens.append(None)
            return
        self.tokens.append(self._token)
        self._tokens.add(self._token)

    def on_ack(self, ack: Any) -> None:
        if ack.opcode == protocols.CommandCode.DECISION and ack.token in self._tokens:
            self._tokens.discard(ack.token)
            self.count_ack(ack)
