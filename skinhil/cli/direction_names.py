"""Display names of the direction classes, shared by the commands that print decisions."""

from __future__ import annotations


def class_names() -> dict[int, str]:
    """Display names of the direction classes (stimulus id → name)."""
    from skinhil.model.stimuli import direction_conditions

    return {i: s.name for i, s in enumerate(direction_conditions())}
