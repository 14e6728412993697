"""The stimulus table a board publishes (SPEC.md §3.7): every stimulus id it knows, by name.

The ids are those of the ground-truth MARKERs and of SET_STIMULUS: the built-ins (0..8 the
Figure 4 direction conditions, 10..14 the paper's stimuli A-E) and a schedule file's own
stimuli (100, 101, ... in file order). The same table is on the wire (SESSION and STIMULUS
records) and printed by ``skinhil stimuli``.
"""

from __future__ import annotations

from collections.abc import Mapping

from protocols.records import StimulusEntry
from protocols.session_layout import MAX_NAME_BYTES
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.stimuli import Schedule, Stimulus, builtin_catalog


def catalog(size: MeshSize = PAPER_SIZE, schedule: Schedule | None = None
            ) -> dict[int, Stimulus]:
    """Every stimulus a board of top-layer ``size`` knows, by id: the built-ins, then the
    schedule file's stimuli (a built-in keeps its id)."""
    out: dict[int, Stimulus] = {sid: s for sid, s in builtin_catalog(size).values()}
    if schedule is not None:
        for e in schedule.entries:
            out.setdefault(e.stimulus_id, e.stimulus)
    return out


def wire_name(name: str) -> str:
    """``name`` cut to at most 64 UTF-8 bytes on a character boundary (a STIMULUS record's
    limit; names of schedule files have at most 64 characters)."""
    raw = name.encode("utf-8")[:MAX_NAME_BYTES]
    return raw.decode("utf-8", errors="ignore") or "?"


def stimulus_table(stimuli: Mapping[int, Stimulus]) -> list[StimulusEntry]:
    """The table's rows in ascending id order."""
    return [StimulusEntry(sid, wire_name(stimuli[sid].name)) for sid in sorted(stimuli)]
