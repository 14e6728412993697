"""The live view's feed: a receiver listener that turns the stream into update messages.

:class:`ViewFeed` hears the receiver's callbacks (on the receiving thread) and keeps what
arrived since the last update; :meth:`ViewFeed.update` (on the view's publishing thread,
every 0.1 s) drains it into one JSON-ready message:

- ``t_board_us``: the newest board time seen (µs): events, markers and STATUS records move
  it, so a quiet board's page goes on;
- ``run``: the run's state (:meth:`ViewFeed.run_state`): ``waiting`` (nothing received
  yet), ``live``, ``silent`` (nothing from the board for :data:`SILENT_S` s), ``stopped``
  (the board's STATUS says it does not publish), ``link lost`` or ``ended`` (the receiver
  stopped, or :meth:`ViewFeed.end_run` said so: the board's end-of-run record will), with a
  ``reason`` to show;
- ``spikes``: the new events as base64 of little-endian arrays, ``t`` (uint32, µs after
  ``t0_us``) and ``addr`` (uint16), at most :data:`MAX_SPIKES_PER_UPDATE` (the rest are
  counted in ``spikes_not_drawn``, never silently left out);
- ``psp``: the new PSP samples of the chosen sensors (base64 float32, row-major, samples ×
  sensors, from sample index ``first`` at ``rate_hz``);
- ``decisions``: the new decisions, each with its ground truth; ``markers``: the new
  ground-truth markers;
- ``score``: the running confusion matrix (rows true, columns decided), accuracy, misses,
  false alarms; ``link``: the receiver's link and loss counters; ``board``: the board's
  last status (late ticks, drops by reason);
- ``map``: the skin map (:class:`skinhil.view.rate_map.RateMap`): each place's spike rate
  above its sensors' own baselines as a z-score, ``z`` (base64 float32, row-major over the
  ``map_shape`` places of the ``config``), and the mean baseline ``baseline_hz``;
- ``seq``: the update's number (1, 2, ...);
- ``psp_sensors`` and ``psp_labels``: present when the PSP sensors changed (a page picked
  one, :meth:`ViewFeed.pick_psp_sensors`);
- ``grasp``: present when the feed has a held object's truth (``demo --task grasp
  --view``): its new points and lift outcomes (:class:`skinhil.view.grasp_trace.GraspTrace`),
  what the grasp panel plots; the ``config`` then holds the last seconds of them;
- ``answers``: present when the receiver answers the board (``listen --answer``, ``demo``):
  its DECISIONs sent, ACKed, NACKed and not sent, shown in their own panel (the board's
  verdicts on them are its scoreboard: ``serve``'s status line and ``--score``).

The ``config`` message a page gets first says what does not change: the channels, the
class names, the PSP sensors, the skin's top layer (``grid`` rows, cols) and each sensor's
place on it (``sensor_xy``: base64 float32 pairs, column then row in grid units from the
top-left mass, its spring's midpoint at rest), the skin map's places (``map_shape``: rows,
cols of half-cells) and its latest ``map``; and ``history``: the updates of the last
:data:`HISTORY_S` board seconds (their spikes, markers, PSP samples), which the page draws
before the next update (the one after the last ``seq`` of the history), so a page opened
late is not empty.

Onsets come from the stream's ground-truth markers, and also from the operator's truth
(:meth:`ViewFeed.add_truth_onsets`: ``listen --view --view-truth FILE``; never from the
decoder's link), each marker then saying its ``source``.

Nothing here copies the session: each message holds only what arrived since the last one.
"""

from __future__ import annotations

import base64
import dataclasses
import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np

from skinhil.model.geometry import Mesh, sensor_label, sensor_positions
from skinhil.receiver import LinkReport, ReceiverListener, ScoredDecision, in_stream_order
from skinhil.receiver.traces import PspTraces
from skinhil.view.grasp_trace import GraspTrace
from skinhil.view.rate_map import RateMap

log = logging.getLogger(__name__)

MAX_SPIKES_PER_UPDATE = 200_000
"""Most spikes one update carries (2 Mspikes/s at 10 updates/s); the rest are counted."""

RECENT_DECISIONS = 18
"""Decisions a page that connects is shown first (the newest, in the ``config`` event)."""

DEFAULT_TRACES = 8
"""PSP traces shown when none are chosen: this many sensors spread over the addresses."""

MAX_TRACES = 16
"""Most PSP traces a page may pick."""

SILENT_S = 3.0
"""Host seconds without anything from the board after which the run is called silent."""

HISTORY_S = 10.0
"""Board seconds of updates a page that connects gets first (the raster's width)."""


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def grid_xy(mesh: Mesh) -> np.ndarray:
    """(n_sensors, 2) float32: each sensor's place on the top layer in grid units, column
    (0 at the left mass) then row (0 at the top mass), from its rest position."""
    where = sensor_positions(mesh)
    rows, cols = mesh.size
    top = mesh.positions[: rows * cols]
    spacing = float(top[1, 0] - top[0, 0]) if cols > 1 else 1.0
    col = (where[:, 0] - top[:, 0].min()) / spacing
    row = (top[:, 1].max() - where[:, 1]) / spacing
    return np.stack([col, row], axis=1).astype(np.float32)


def default_trace_sensors(n_channels: int, count: int = DEFAULT_TRACES) -> list[int]:
    """``count`` sensor addresses spread evenly over ``0..n_channels-1``."""
    return sorted({int(a) for a in np.linspace(0, n_channels - 1, min(count, n_channels))})


class StreamSource(Protocol):
    """What the feed reads of the receiving end (:class:`skinhil.receiver.Receiver`,
    :class:`skinhil.receiver.grip_loop.GripLoop`); a ``scoreboard`` attribute, where it has
    one, gives the ``score`` (None without)."""

    last_status: Any

    def link_report(self) -> LinkReport: ...


class ViewFeed(ReceiverListener):
    """Receiver listener → update messages of the live view (see the module)."""

    def __init__(self, receiver: StreamSource, mesh: Mesh, names: dict[int, str],
                 psp_sensors: Sequence[int] | None = None,
                 answers: Callable[[], dict[str, int]] | None = None,
                 grasp: GraspTrace | None = None) -> None:
        self.receiver = receiver
        self.grasp = grasp
        """The held object's truth for the grasp panel (added by the operator that runs
        the board, never read from the link), or None: no panel."""
        self.names = names
        self.mesh = mesh
        self.n_channels = int(mesh.springs.shape[0])
        sensors = (default_trace_sensors(self.n_channels) if psp_sensors is None
                   else [int(s) for s in psp_sensors])
        self.traces = PspTraces(sensors, self.n_channels)
        self.answers = answers
        """The receiver's DECISION counters (``DecisionAnswerer.as_dict``), if it answers."""
        xy = grid_xy(mesh)
        self.rate_map = RateMap(xy, (int(mesh.size[0]), int(mesh.size[1])))
        self.config = {
            "type": "config", "n_channels": self.n_channels,
            "names": {str(k): v for k, v in names.items()},
            "psp_sensors": sensors, "psp_rate_hz": self.traces.rate_hz,
            "psp_labels": [sensor_label(mesh, a) for a in sensors], "max_traces": MAX_TRACES,
            "grid": [int(mesh.size[0]), int(mesh.size[1])],
            "sensor_xy": _b64(xy.astype("<f4")),
            "map_shape": [self.rate_map.rows, self.rate_map.cols]}
        self._lock = threading.Lock()
        self._traces_changed = False
        self._last_item_s = -math.inf
        """Host monotonic time (s) of the newest item from the board."""
        self._board_stopped = False
        self._link_lost: str | None = None
        self._ended: str | None = None
        self._events: list[np.ndarray] = []
        self._psp: list[np.ndarray] = []
        self._psp_first = -1
        self._decisions: list[dict[str, Any]] = []
        self._recent: deque[dict[str, Any]] = deque(maxlen=RECENT_DECISIONS)
        self._markers: list[dict[str, Any]] = []
        self._link_errors: list[str] = []
        self._t_board_us = 0
        self.updates = 0
        self._history: deque[dict[str, Any]] = deque()
        self._map: dict[str, Any] = self._map_message()

    # -- receiver callbacks (receiving thread) --------------------------------------------
    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        if events.shape[0] == 0:
            return
        with self._lock:
            self.traces.add(events)
            self.rate_map.add(events["addr"])
            self._events.append(events[["t", "addr"]].copy())
            self._t_board_us = max(self._t_board_us, int(events["t"][-1]))
            self._heard(host_time_s)
        self._advance_traces(int(events["t"][-1]))

    def _heard(self, host_s: float | None = None) -> None:
        """Something came from the board (lock held)."""
        self._last_item_s = time.monotonic() if host_s is None else host_s
        self._link_lost = None

    def _advance_traces(self, board_t_us: int) -> None:
        with self._lock:
            first, values = self.traces.advance(board_t_us)
            if values.shape[0]:
                if not self._psp:
                    self._psp_first = first
                self._psp.append(values)

    def on_status(self, status: Any) -> None:
        """A STATUS moves the clock (and the traces, when no event was queued before it:
        :func:`skinhil.receiver.in_stream_order`), and says whether the board publishes."""
        t = int(status.t_us)
        with self._lock:
            self._t_board_us = max(self._t_board_us, t)
            self._board_stopped = not bool(status.running)
            self._heard()
        if in_stream_order(status):
            self._advance_traces(t)

    def pick_psp_sensors(self, sensors: Sequence[int]) -> list[int]:
        """Show the PSP traces of ``sensors`` from now on (a page picked them); invalid
        addresses, repeats and those past :data:`MAX_TRACES` are left out; return those
        shown."""
        chosen = list(dict.fromkeys(int(a) for a in sensors
                                    if 0 <= int(a) < self.n_channels))[:MAX_TRACES]
        if not chosen:
            return [int(a) for a in self.traces.channels]
        with self._lock:
            traces = PspTraces(chosen, self.n_channels)
            if self.traces.next_sample >= 0:
                traces.advance(self.traces.next_sample * self.traces.sample_us)
            self.traces = traces
            self._psp, self._psp_first = [], -1
            self._traces_changed = True
            for old in self._history:  # samples of the sensors shown before: not replayed
                old["psp"] = {"first": -1, "n": 0, "values": ""}
            self.config = {**self.config, "psp_sensors": chosen,
                           "psp_labels": [sensor_label(self.mesh, a) for a in chosen]}
        return chosen

    def end_run(self, reason: str) -> None:
        """The run is over (``reason`` is shown): the receiver stopped, or the board said so
        (its end-of-run record)."""
        with self._lock:
            if self._ended is None:
                self._ended = reason

    def run_state(self, now_s: float | None = None) -> dict[str, str]:
        """``{"state": ..., "reason": ...}``: see the module."""
        now = time.monotonic() if now_s is None else now_s
        with self._lock:
            if self._ended is not None:
                return {"state": "ended", "reason": self._ended}
            if self._link_lost is not None:
                return {"state": "link lost", "reason": self._link_lost}
            if not math.isfinite(self._last_item_s):
                return {"state": "waiting", "reason": "nothing received from the board yet"}
            quiet = now - self._last_item_s
            if quiet >= SILENT_S:
                return {"state": "silent",
                        "reason": f"nothing from the board for {quiet:.0f} s"}
            if self._board_stopped:
                return {"state": "stopped", "reason": "the board does not publish "
                                                      "(its STATUS says stopped)"}
            return {"state": "live", "reason": ""}

    def on_marker(self, marker: Any) -> None:
        sid = int(marker.stimulus_id)
        with self._lock:
            self._markers.append({"t_us": int(marker.t_us), "stimulus_id": sid,
                                  "phase": getattr(marker.phase, "name",
                                                   str(marker.phase)).lower(),
                                  "source": "marker"})
            self._t_board_us = max(self._t_board_us, int(marker.t_us))
            self._heard()

    def add_truth_onsets(self, onsets: Sequence[dict[str, Any]]) -> None:
        """Show the operator's truth (:mod:`skinhil.view.truth_onsets`): each a dict with
        ``t_us`` (board µs), ``phase`` (``onset`` or ``end``), ``label`` (what the page
        writes) and, for a marker, ``stimulus_id``; drawn as the markers are, with
        ``source`` ``truth``."""
        with self._lock:
            self._markers.extend({**o, "source": "truth"} for o in onsets)

    def on_decision(self, decision: ScoredDecision) -> None:
        p = decision.prediction
        lat = decision.latency_board_s
        item = {"t_us": int(p.decided_t_us), "detect_t_us": int(p.detect_t_us),
                "label": int(p.label), "true_label": decision.true_label,
                "correct": decision.correct,
                "latency_ms": None if lat is None or math.isnan(lat) else round(1e3 * lat, 2)}
        with self._lock:
            self._decisions.append(item)
            self._recent.append(item)

    def hello(self) -> dict[str, Any]:
        """The ``config`` message a page gets first: channels, names, PSP sensors and the
        newest decisions (oldest first)."""
        with self._lock:
            recent = list(self._recent)
            history = list(self._history)
            rate_map = self._map
        hello = {**self.config, "recent_decisions": recent, "history": history,
                 "map": rate_map}
        if self.grasp is not None:
            hello["grasp"] = self.grasp.history()
        return hello

    def on_link_error(self, message: str) -> None:
        with self._lock:
            self._link_errors.append(message)
            self._link_lost = message

    # -- updates (publishing thread) ------------------------------------------------------
    def update(self) -> dict[str, Any]:
        """The message of everything received since the previous call (see the module)."""
        with self._lock:
            events, self._events = self._events, []
            psp, self._psp = self._psp, []
            psp_first = self._psp_first
            decisions, self._decisions = self._decisions, []
            markers, self._markers = self._markers, []
            errors, self._link_errors = self._link_errors, []
            t_board = self._t_board_us
            changed, self._traces_changed = self._traces_changed, False
            n_traces = self.traces.channels.size
        self.updates += 1
        msg: dict[str, Any] = {"type": "update", "t_board_us": t_board,
                               "decisions": decisions, "markers": markers,
                               "link_errors": errors, "run": self.run_state()}
        if changed:
            msg["psp_sensors"] = self.config["psp_sensors"]
            msg["psp_labels"] = self.config["psp_labels"]
        ev = np.concatenate(events) if events else np.zeros(0, [("t", "<i8"), ("addr", "<u2")])
        not_drawn = max(0, ev.shape[0] - MAX_SPIKES_PER_UPDATE)
        ev = ev[not_drawn:]
        t0 = int(ev["t"][0]) if ev.shape[0] else t_board
        msg["spikes"] = {"n": int(ev.shape[0]), "t0_us": t0,
                         "t": _b64((ev["t"] - t0).astype("<u4")),
                         "addr": _b64(ev["addr"].astype("<u2")),
                         "not_drawn": not_drawn}
        values = np.concatenate(psp) if psp else np.zeros((0, n_traces), dtype=np.float32)
        msg["psp"] = {"first": psp_first, "n": int(values.shape[0]),
                      "values": _b64(values.astype("<f4"))}
        msg["score"] = self._score()
        msg["link"] = self.receiver.link_report().as_dict()
        st = self.receiver.last_status
        msg["board"] = None if st is None else {
            k: v for k, v in dataclasses.asdict(st).items() if isinstance(v, int | bool)}
        if self.answers is not None:
            msg["answers"] = self.answers()
        if self.grasp is not None:
            msg["grasp"] = self.grasp.drain()
        with self._lock:
            self.rate_map.advance(t_board)
            self._map = msg["map"] = self._map_message()
            msg["seq"] = self.updates
            self._keep(msg)
        return msg

    def _map_message(self) -> dict[str, Any]:
        """The skin map's ``map`` item (lock held)."""
        return {"z": _b64(self.rate_map.z.astype("<f4")),
                "baseline_hz": round(float(self.rate_map.baseline_hz().mean()), 3)}

    def _keep(self, msg: dict[str, Any]) -> None:
        """Keep what a late page draws of ``msg`` (its spikes, markers, PSP samples) for
        :data:`HISTORY_S` board seconds (lock held); an update that brought none of them
        is not kept (a board not started yet fills nothing)."""
        if not (msg["spikes"]["n"] or msg["markers"] or msg["psp"]["n"]):
            return
        self._history.append({
            "type": "update", "seq": msg["seq"], "t_board_us": msg["t_board_us"],
            "spikes": msg["spikes"], "markers": msg["markers"], "psp": msg["psp"],
            "decisions": [], "link_errors": [], "run": msg["run"]})
        horizon = msg["t_board_us"] - int(HISTORY_S * 1e6)
        while self._history and self._history[0]["t_board_us"] < horizon:
            self._history.popleft()

    def _score(self) -> dict[str, Any] | None:
        sb = getattr(self.receiver, "scoreboard", None)
        if sb is None:
            return None
        return {"classes": list(sb.classes), "confusion": sb.confusion.tolist(),
                "scored": sb.scored, "correct": sb.correct, "misses": sb.misses,
                "false_alarms": sb.false_alarms,
                "accuracy": None if sb.scored == 0 else sb.accuracy}
