"""The one rule that matches a decision to the stimulus it answers, for the board and the
receiver alike.

A decision at board time ``t_us`` answers the **latest onset at or before** ``t_us``. With
``window_us`` the response window and ``t0`` that onset's time:

- ``t_us - t0 <= window_us`` and the onset has no decision yet: :attr:`MatchKind.MATCHED`
  (the onset is now decided);
- ``t_us - t0 <= window_us`` and the onset already has one: :attr:`MatchKind.DUPLICATE`;
- ``t_us - t0 > window_us`` and the onset never got one: :attr:`MatchKind.LATE`;
- no onset at or before ``t_us``, or ``t_us - t0 > window_us`` after a decided onset:
  :attr:`MatchKind.NO_STIMULUS`.

An onset still undecided once board time passes ``t0 + window_us`` is a **miss**
(:meth:`OnsetMatcher.resolve`). The receiver matches a decision at the board time it was
made, the board at a DECISION's arrival (``protocols/SPEC.md`` §3.5.2): the same rule, the
board's time later by the decoder's link alone.
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass


class MatchKind(enum.Enum):
    """What a decision is to the latest onset before it (see the module rule)."""

    MATCHED = "matched"
    DUPLICATE = "duplicate"
    LATE = "late"
    NO_STIMULUS = "no_stimulus"


@dataclass
class Onset:
    """A ground-truth onset: stimulus ``stimulus_id`` started at board time ``t_us`` (µs)."""

    t_us: int
    stimulus_id: int
    decided: bool = False
    """True once a decision matched it."""
    resolved: bool = False
    """True once its window passed: decided, or counted as a miss."""


@dataclass(frozen=True)
class Match:
    """The verdict of :meth:`OnsetMatcher.match`: its kind and the onset it concerns (None
    when there is no onset before the decision)."""

    kind: MatchKind
    onset: Onset | None


class OnsetMatcher:
    """Onsets in time order and the module's rule; ``window_us`` the response window (µs).

    Memory is bounded: onsets whose miss verdict is given are forgotten, except the latest
    (a later decision is still told apart as late or no-stimulus against it).
    """

    def __init__(self, window_us: int) -> None:
        self.window_us = int(window_us)
        self._open: deque[Onset] = deque()
        """Onsets not yet resolved (and the latest one, always)."""
        self.onsets = 0
        """Onsets added."""
        self.misses = 0
        """Onsets resolved without a decision."""

    def add_onset(self, t_us: int, stimulus_id: int) -> None:
        """Add the onset of ``stimulus_id`` at board time ``t_us`` (µs), in time order."""
        self._open.append(Onset(int(t_us), int(stimulus_id)))
        self.onsets += 1

    def match(self, t_us: int) -> Match:
        """Match a decision at board time ``t_us`` (µs) by the module's rule; a MATCHED
        onset is marked decided."""
        for onset in reversed(self._open):
            if onset.t_us <= t_us:
                break
        else:
            return Match(MatchKind.NO_STIMULUS, None)
        if t_us - onset.t_us <= self.window_us and not (onset.resolved and not onset.decided):
            if onset.decided:
                return Match(MatchKind.DUPLICATE, onset)
            onset.decided = True
            return Match(MatchKind.MATCHED, onset)
        if onset.decided:
            return Match(MatchKind.NO_STIMULUS, onset)
        return Match(MatchKind.LATE, onset)  # its miss is (or will be) counted

    def resolve(self, now_us: int) -> int:
        """Give the miss verdict of every onset whose window has passed by board
        time ``now_us`` (µs) without a decision; return how many new misses."""
        new = 0
        for onset in self._open:
            if onset.resolved:
                continue
            if onset.t_us + self.window_us >= now_us:
                break
            onset.resolved = True
            new += not onset.decided
        while len(self._open) > 1 and self._open[0].resolved:
            self._open.popleft()
        self.misses += new
        return new

    @property
    def pending(self) -> int:
        """Onsets neither decided nor missed yet."""
        return sum(1 for o in self._open if not (o.decided or o.resolved))
