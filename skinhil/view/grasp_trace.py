"""The live view's grasp panel data: the held object's truth (:data:`skinhil.plant.HELD_DTYPE`
records, one a tick, from the board's truth log: never from the decoder's link) decimated for
the page.

:meth:`GraspTrace.add` takes the records as they come (any thread); the view's feed puts
:meth:`GraspTrace.drain` into each update as ``grasp`` and :meth:`GraspTrace.history` into
the ``config`` a page gets first (the last :data:`HISTORY_S` s, so a page that connects late
still sees the lifts so far). Each point stands for one bin of :data:`BIN_US` of board time
(10 points per 0.1 s update): ``t_us`` (the bin's last tick), ``grip_n``, ``normal_n``,
``load_n`` (N) and ``slip_mm`` (mm) of the bin's last tick, ``slip`` the bin's highest slip
state (0 none, 1 stick, 2 partial, 3 gross: a short slip is not lost), ``lift`` its lift
(0 between lifts). ``grip_n`` is the grip on the object, the hand's set-point while the tick
holds it (``held``), None when no object is held (between lifts, and from the tick a lift's
object dropped: the board grips it no more), so the plotted grip ends at the drop.
``outcomes`` marks each lift's end: ``{"lift", "t_us", "held"}`` at the tick it dropped, or
at its last tick when it was held.
"""

from __future__ import annotations

import threading
from collections import deque
from typing import Any

import numpy as np

BIN_US = 10_000
"""Board time (µs) one plotted point stands for."""

HISTORY_S = 12.0
"""Board seconds of points a page that connects gets first (the panel shows 10 s)."""

FIELDS = (("grip_n", "grip_n"), ("normal_n", "normal_n"), ("load_n", "load_n"),
          ("slip_mm", "slip_distance_mm"))
"""(message key, record field) of the points' forces and distance, 4 decimals."""


class GraspTrace:
    """The held object's truth, binned for the live view (see the module)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending = np.zeros(0, dtype=[("t_us", "<i8")])
        self._points: list[dict[str, Any]] = []
        self._outcomes: list[dict[str, Any]] = []
        self._history: deque[dict[str, Any]] = deque(
            maxlen=int(HISTORY_S * 1e6 / BIN_US))
        self._history_outcomes: deque[dict[str, Any]] = deque(maxlen=64)
        self._lift = 0
        self._lift_last_us = 0
        self._lift_dropped = False
        self.records = 0
        """Records added so far."""

    def add(self, records: np.ndarray) -> None:
        """Add held-object records (time order); whole bins become points, the open bin
        waits for its next records (or :meth:`finish`)."""
        if records.shape[0] == 0:
            return
        with self._lock:
            self.records += int(records.shape[0])
            rec = (np.concatenate([self._pending, records]) if self._pending.shape[0]
                   else records)
            last_bin = int(rec["t_us"][-1]) // BIN_US
            whole = rec["t_us"] // BIN_US < last_bin
            self._pending = rec[~whole]
            self._binned(rec[whole])

    def finish(self) -> None:
        """The run is over: the open bin becomes a point, a lift still running gets its
        outcome."""
        with self._lock:
            rec, self._pending = self._pending, self._pending[:0]
            if rec.shape[0]:
                self._binned(rec)
            self._end_lift()

    def _binned(self, rec: np.ndarray) -> None:
        """Points and outcomes of ``rec`` (whole bins; lock held)."""
        if rec.shape[0] == 0:
            return
        for k in range(rec.shape[0]):  # lift ends and drops, tick by tick
            lift, dropped = int(rec["lift"][k]), bool(rec["dropped"][k])
            if lift != self._lift:
                self._end_lift()
                self._lift, self._lift_dropped = lift, False
            if lift and dropped and not self._lift_dropped:
                self._lift_dropped = True
                self._outcome(lift, int(rec["t_us"][k]), False)
            self._lift_last_us = int(rec["t_us"][k])
        bins = rec["t_us"] // BIN_US
        ends = np.flatnonzero(np.r_[bins[1:] != bins[:-1], True])
        starts = np.r_[0, ends[:-1] + 1]
        slip = np.maximum.reduceat(rec["slip"].astype(np.int64), starts)
        for i, e in enumerate(ends.tolist()):
            point: dict[str, Any] = {"t_us": int(rec["t_us"][e]), "lift": int(rec["lift"][e]),
                     "slip": int(slip[i])}
            for key, field in FIELDS:
                point[key] = round(float(rec[field][e]), 4)
            if not rec["held"][e]:
                point["grip_n"] = None  # no object in the hand: nothing gripped
            self._points.append(point)
            self._history.append(point)

    def _end_lift(self) -> None:
        """The running lift ended: held unless it dropped (lock held)."""
        if self._lift and not self._lift_dropped:
            self._outcome(self._lift, self._lift_last_us, True)
        self._lift_dropped = True  # one outcome a lift

    def _outcome(self, lift: int, t_us: int, held: bool) -> None:
        mark = {"lift": lift, "t_us": t_us, "held": held}
        self._outcomes.append(mark)
        self._history_outcomes.append(mark)

    @staticmethod
    def _columns(points: list[dict[str, Any]], outcomes: list[dict[str, Any]]
                 ) -> dict[str, Any]:
        keys = ("t_us", "lift", "slip", *(k for k, _ in FIELDS))
        return {**{k: [p[k] for p in points] for k in keys}, "outcomes": outcomes}

    def drain(self) -> dict[str, Any]:
        """The points and outcomes since the last call, as columns (see the module)."""
        with self._lock:
            points, self._points = self._points, []
            outcomes, self._outcomes = self._outcomes, []
        return self._columns(points, outcomes)

    def history(self) -> dict[str, Any]:
        """The last :data:`HISTORY_S` s of points and their lifts' outcomes, as columns."""
        with self._lock:
            points = list(self._history)
            first = points[0]["t_us"] if points else 0
            outcomes = [m for m in self._history_outcomes if m["t_us"] >= first]
        return self._columns(points, outcomes)
