"""The operator's truth on the live view: onsets read from a file, never from the link.

``listen --view --view-truth FILE`` reads FILE, the board's ground truth as ``serve --truth``
writes it (JSON lines: ``{"type": "marker", "t_us", "stimulus_id", "phase"}`` for each
stimulus marker, ``{"type": "trial", "task", "t_us", "contact", ...}`` for each trial of a
contact task), and draws its onsets on the raster and the PSP traces beside the stream's
markers: a contact scenario, whose touches send no marker, shows where each touch began.
The file may appear, grow or be rewritten whole while the view runs: :class:`TruthTail`
reads it again every :data:`POLL_S` seconds and hands on each onset once. The truth
reaches the view only from the operator's file: the decoder's link never carries it.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

POLL_S = 0.5
"""Seconds between readings of the truth file."""


def truth_onsets(lines: Sequence[str]) -> list[dict[str, Any]]:
    """The onsets and ends of the truth file's ``lines`` (see the module), in the view's
    marker form: ``t_us`` (board µs), ``phase`` (``onset`` or ``end``), ``label`` (a
    marker's: None, the page names its stimulus; a trial's: ``contact N``) and ``key`` (the
    same onset told twice, e.g. one contact's trial in two tasks, has one key). Lines that
    are not JSON objects of those types are left out."""
    out: dict[tuple[Any, ...], dict[str, Any]] = {}
    for line in lines:
        try:
            rec = json.loads(line)
            t_us = int(rec["t_us"])
        except (ValueError, TypeError, KeyError):
            continue
        if not isinstance(rec, dict):
            continue
        if rec.get("type") == "marker":
            phase = str(rec.get("phase", "onset")).lower()
            sid = rec.get("stimulus_id")
            key: tuple[Any, ...] = ("marker", t_us, sid, phase)
            out.setdefault(key, {"t_us": t_us, "phase": phase, "stimulus_id": sid,
                                 "label": None})
        elif rec.get("type") == "trial":
            contact = rec.get("contact")
            key = ("contact", t_us, contact)
            out.setdefault(key, {"t_us": t_us, "phase": "onset", "stimulus_id": None,
                                 "label": f"contact {contact}"})
        else:
            continue
        out[key]["key"] = "/".join(map(str, key))
    return sorted(out.values(), key=lambda o: int(o["t_us"]))


class TruthTail:
    """Read ``path`` every :data:`POLL_S` s on a thread and hand each new onset to
    ``sink`` once (:meth:`skinhil.view.ViewFeed.add_truth_onsets`); a missing file waits."""

    def __init__(self, path: Path, sink: Callable[[list[dict[str, Any]]], None]) -> None:
        self.path = Path(path)
        self.sink = sink
        self._seen: set[str] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="skinhil-view-truth",
                                        daemon=True)

    def poll(self) -> int:
        """Read the file once; hand on its new onsets; return how many."""
        try:
            text = self.path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return 0
        new = [o for o in truth_onsets(text.splitlines()) if o["key"] not in self._seen]
        self._seen.update(o["key"] for o in new)
        if new:
            self.sink(new)
        return len(new)

    def start(self) -> TruthTail:
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.is_set():
            self.poll()
            self._stop.wait(POLL_S)

    def close(self) -> None:
        """Stop reading (after a last reading)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.poll()
