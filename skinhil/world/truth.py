"""The ground truth of every contact, one record per contact per tick.

A numpy structured array (:data:`TRUTH_DTYPE`), units in the field names: board time, which
contact, the contact's centroid (the normal-force-weighted mean of its touching masses'
current positions) and area (touching masses × spacing²), the normal and tangential force
the indenter exerts on the skin, the slip state (:data:`SLIP_STATES`) and slip speed (the
normal-force-weighted mean speed of the slipping masses relative to the indenter), the
indenter's pose and its load set-point (force control; NaN under position control).

It is the board's secret: written by ``simulate`` and kept by the board (for scoring and
recordings), never sent on the decoder's link.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import numpy as np

SLIP_STATES = ("none", "stick", "partial", "gross")
"""``slip`` codes: no mass touching; every touching mass sticks; some slip (at the contact's
edge first); all slip."""

(T_ACTIVE, T_X, T_Y, T_AREA, T_NORMAL, T_FX, T_FY, T_SLIP, T_SLIP_SPEED, T_NODES, T_IX, T_IY,
 T_DEPTH, T_LOAD) = range(14)
TRUTH_PERIOD_S = 1e-3
"""One truth record per contact per this period (s): the board's tick, the state at its
start."""
RAW_FIELDS = 14
"""Columns of the compiled kernel's per-step truth (SI units: m, m², N, m/s)."""

TRUTH_DTYPE = np.dtype([
    ("t_us", "<i8"), ("contact", "<u2"), ("active", "?"), ("nodes", "<u2"),
    ("x_mm", "<f8"), ("y_mm", "<f8"), ("area_mm2", "<f8"),
    ("normal_n", "<f8"), ("tangential_n", "<f8"), ("tangential_x_n", "<f8"),
    ("tangential_y_n", "<f8"), ("slip", "u1"), ("slip_speed_mm_per_s", "<f8"),
    ("indenter_x_mm", "<f8"), ("indenter_y_mm", "<f8"), ("indenter_depth_mm", "<f8"),
    ("load_n", "<f8"),
])
"""One contact at one tick. ``active``: its trajectory is running; ``nodes``: top-layer
masses touching; ``x_mm``, ``y_mm``: centroid (NaN when nothing touches); ``slip``: a code of
:data:`SLIP_STATES`; ``indenter_*``: the axis and the tip's depth below the rest surface
(NaN while not active); ``load_n``: the normal load set-point (NaN under position
control)."""


def truth_records(raw: np.ndarray, t_us: np.ndarray) -> np.ndarray:
    """Records (:data:`TRUTH_DTYPE`, time-major then contact) from the kernel's per-step
    truth ``raw`` (n, n_contacts, :data:`RAW_FIELDS`) at board times ``t_us`` (n,) µs."""
    n, c = raw.shape[0], raw.shape[1]
    out = np.zeros(n * c, dtype=TRUTH_DTYPE)
    r = raw.reshape(n * c, RAW_FIELDS)
    out["t_us"] = np.repeat(np.asarray(t_us, dtype=np.int64), c)
    out["contact"] = np.tile(np.arange(c), n)
    out["active"] = r[:, T_ACTIVE] > 0
    out["nodes"] = r[:, T_NODES]
    touching = r[:, T_NODES] > 0
    out["x_mm"] = np.where(touching, r[:, T_X] * 1e3, np.nan)
    out["y_mm"] = np.where(touching, r[:, T_Y] * 1e3, np.nan)
    out["area_mm2"] = r[:, T_AREA] * 1e6
    out["normal_n"] = r[:, T_NORMAL]
    out["tangential_x_n"] = r[:, T_FX]
    out["tangential_y_n"] = r[:, T_FY]
    out["tangential_n"] = np.hypot(r[:, T_FX], r[:, T_FY])
    out["slip"] = r[:, T_SLIP]
    out["slip_speed_mm_per_s"] = r[:, T_SLIP_SPEED] * 1e3
    active = r[:, T_ACTIVE] > 0
    out["indenter_x_mm"] = np.where(active, r[:, T_IX] * 1e3, np.nan)
    out["indenter_y_mm"] = np.where(active, r[:, T_IY] * 1e3, np.nan)
    out["indenter_depth_mm"] = np.where(active, r[:, T_DEPTH] * 1e3, np.nan)
    out["load_n"] = r[:, T_LOAD]
    return out


class TruthLog:
    """The latest ticks' truth, a bounded ring of ``capacity_ticks`` (60 s of 1 ms ticks by
    default), as the board keeps it: each tick's kernel rows are copied (a few µs) and
    turned into records only when read; ``ticks`` counts every tick ever added."""

    def __init__(self, capacity_ticks: int = 60_000) -> None:
        self._ticks: deque[tuple[int, np.ndarray]] = deque(maxlen=capacity_ticks)
        self._objects: deque[np.ndarray] = deque(maxlen=capacity_ticks)
        self.ticks = 0
        self.object_sink: Callable[[np.ndarray], None] | None = None
        """Also handed each held-object record as it is added (``serve --grasp-truth``'s
        file), or None."""

    def clear(self) -> None:
        """Forget every kept tick (the board's warm-up is over); the sink stays."""
        self._ticks.clear()
        self._objects.clear()
        self.ticks = 0

    def add_object(self, row: np.ndarray) -> None:
        """Keep one tick's record of a held object (a structured row, the plant's dtype:
        :data:`skinhil.plant.HELD_DTYPE`)."""
        self._objects.append(row.copy())
        if self.object_sink is not None:
            self.object_sink(row)

    def objects(self) -> np.ndarray | None:
        """Every kept tick's held-object records, in time order; None when none were kept."""
        return np.concatenate(list(self._objects)) if self._objects else None

    def add_raw(self, t_us: int, raw: np.ndarray) -> None:
        """Keep one tick's truth: the kernel's rows (n_contacts, :data:`RAW_FIELDS`) for
        board time ``t_us`` (µs); a row-less tick is ignored."""
        if raw.size:
            self._ticks.append((int(t_us), raw.copy()))
            self.ticks += 1

    def records(self) -> np.ndarray:
        """Every kept tick's records, in time order (:data:`TRUTH_DTYPE`)."""
        if not self._ticks:
            return np.zeros(0, dtype=TRUTH_DTYPE)
        t_us = np.array([t for t, _ in self._ticks], dtype=np.int64)
        return truth_records(np.stack([r for _, r in self._ticks]), t_us)

    def latest(self) -> np.ndarray:
        """The last tick's records (one per contact), or none."""
        if not self._ticks:
            return np.zeros(0, dtype=TRUTH_DTYPE)
        t_us, raw = self._ticks[-1]
        return truth_records(raw[None], np.array([t_us]))
