"""How many host commands the board executes and answers per tick (SPEC.md §3.6 "Flow
control"): a decoder under test that floods the board cannot take its real time or its wire.

Two limits, applied in the order commands arrive within one tick:

- **execution**: at most :data:`COMMANDS_PER_TICK` commands (DECISIONs included) are executed
  per tick, the CPU a tick spends on them bounded;
- **answers**: every ACK or NACK takes wire time the events need, so answers come from a
  token bucket that refills with :data:`ANSWER_SHARE` of the wire's time per tick, in answers
  of the link's size (at most :data:`ANSWER_BURST` saved up).

A command beyond the execution or answer limit waits in a queue of :data:`PENDING_COMMANDS`
(executed in arrival order in the next ticks, a DECISION stamped with its arrival's board
time); one that finds the queue full is not executed: it is refused as BUSY, counted in
``rx_errors`` (on the wire in every STATUS) and in ``busy``, and answered with a NACK of
reason BUSY while the answer bucket has a token; without one it stays unanswered (the count
says it was refused). QUERY_STATUS is always executed and answered, in its turn, or at once
when the queue is full (its ACK may take the bucket below zero, by at most
:data:`ANSWER_BURST`); a STATUS follows the tick's first at once, and one more STATUS at the
end of the tick answers the others.
"""

from __future__ import annotations

COMMANDS_PER_TICK = 8
"""Host commands executed per tick at most (QUERY_STATUS apart)."""
PENDING_COMMANDS = 64
"""Host commands received and waiting for their turn at most: a burst (a decoder that fell
behind and sends its decisions at once) is executed over the next ticks, each DECISION
stamped with its arrival; a command that finds the queue full is refused BUSY."""
ANSWER_SHARE = 0.25
"""Share of the wire's time the board's answers (ACK, NACK) may take on average."""
ANSWER_BURST = 16.0
"""Answers the bucket saves up at most (a burst of commands after a quiet time)."""


class CommandBudget:
    """The per-tick limits of one link: ``tick_s`` the tick (s), ``answer_wire_s`` the wire
    time (s) of one ACK on that link."""

    def __init__(self, tick_s: float, answer_wire_s: float) -> None:
        self.answers_per_tick = min(float(COMMANDS_PER_TICK),
                                    ANSWER_SHARE * tick_s / max(answer_wire_s, 1e-12))
        """Tokens the answer bucket gains per tick."""
        self._tokens = ANSWER_BURST
        self._executed = 0

    def new_tick(self) -> None:
        """Start a tick: the execution count reset, the bucket refilled."""
        self._executed = 0
        self._tokens = min(ANSWER_BURST, self._tokens + self.answers_per_tick)

    def admit(self) -> bool:
        """Whether a command may be executed and answered now (takes its share if so)."""
        if self._executed >= COMMANDS_PER_TICK or self._tokens < 1.0:
            return False
        self._executed += 1
        self._tokens -= 1.0
        return True

    def admit_query(self) -> None:
        """A QUERY_STATUS, always executed: its answer takes a token, down to −burst."""
        self._tokens = max(-ANSWER_BURST, self._tokens - 1.0)

    def answer_busy(self) -> bool:
        """Whether a refused command gets its BUSY NACK (takes a token if so)."""
        if self._tokens < 1.0:
            return False
        self._tokens -= 1.0
        return True
