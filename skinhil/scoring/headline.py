"""A task's headline ``score`` (SPEC.md §3.5.4), one rule for the contact tasks'
ANSWERs and the classification's DECISIONs: every answer is charged, and a trial answered
more than once scores no right answer."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class HedgedTrials:
    """The trials (keys: trial index or onset time) whose first answer was right, and those
    that got a further answer within their window (a duplicate)."""

    right: set[int] = field(default_factory=set)
    again: set[int] = field(default_factory=set)

    @property
    def voided(self) -> int:
        """Right trials answered more than once: they score no right answer."""
        return len(self.right & self.again)


def headline(right: int, hedges: HedgedTrials, charged: int) -> float | None:
    """A task's ``score`` in [0, 1] (SPEC.md §3.5.4): the trials answered right by their one
    and only answer, over the trials and every answer that did not answer a trial first
    (``charged`` = trials + answers − matched): a second answer to a trial voids its first
    (a decoder that hedges has not answered), and every further or unmatched answer counts
    against the score; None when nothing is charged (no trial, no answer)."""
    if not charged:
        return None
    return round((right - hedges.voided) / charged, 6)


def detection_headline(right: int, hedges: HedgedTrials, trials: int,
                       unmatched: int) -> float | None:
    """A detection task's ``score`` in [0, 1] (SLIP, SPEC.md §3.5.4): a detection has no
    value to be wrong, so only its timing can fail it, and every answer that detects no
    trial (a false alarm during the stick or after the window, a late one, a duplicate)
    cancels one detection: max(0, right − voided − unmatched) / trials. A blind cadence
    detects a trial only by landing in its window, and pays for every beat that does not;
    None when nothing is charged (no trial, no answer)."""
    if not trials:
        return None if not unmatched else 0.0
    return round(max(0, right - hedges.voided - unmatched) / trials, 6)
