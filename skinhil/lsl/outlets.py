"""The LSL outlets of one receiver: spikes, PSP traces, ground-truth markers, decisions,
link health.

Five streams, named ``NAME-spikes``, ``NAME-psp``, ``NAME-markers``, ``NAME-decisions``,
``NAME-link`` (source ids ``skinhil:NAME:...``, so a recorder that loses them finds them
again):

- **spikes** (type ``Spikes``, irregular rate, one ``int32`` channel): one sample per
  spike, its value the sensor (spring) address, stamped at the spike's board time;
- **psp** (type ``PSP``, 1 kHz, one ``float32`` channel per chosen sensor): the eq. 12 PSP
  of each sensor (dimensionless, a spike's kernel peaks at ≈1), stamped at board time;
- **markers** (type ``Markers``, irregular, one string channel): each ground-truth marker
  as ``onset 3 120deg_0.5N t_board_s=12.3456``;
- **decisions** (type ``Markers``, irregular, one string channel): each online decision as
  ``decision 3 120deg_0.5N true=3 correct t_board_s=12.3456`` (board time of the decision);
- **link** (type ``LinkHealth``, irregular, one ``double`` channel per counter of
  :data:`LINK_CHANNELS`): the receiver's link and loss counters and the board's (late
  ticks, events queued, running), one sample per board STATUS stamped at its board time
  and one when the outlets close; an XDF file shows where data were lost where a counter
  steps up.

Every stream's ``desc`` follows the XDF meta-data conventions (:mod:`skinhil.lsl.metadata`):
``acquisition`` and ``provenance`` (version, model, size, SNR, seed, decoder, link), and the
channels LSL tools read: for the psp stream one ``channel`` per sensor (``label`` ``S12
M8-M9``, ``unit`` ``a.u.``, ``type`` ``PSP``, the spring, its two masses and its
``location`` X/Y/Z in mm), for the spikes stream the sensor table (``sensors/sensor``:
address, the spring's two masses, location) and the ``unit`` of the value (``address``).

Spikes and PSP samples are pushed in chunks of :data:`PUSH_PERIOD_US` of board time, and at
every STATUS sent with no event queued (board time known complete: a quiet board's PSP stream
goes on), and whatever is left when the outlets close, up to the newest board time received
(the PSP stream covers the session from the first item received to the last); markers,
decisions and link samples at once.

Time: a sample of board time ``t`` (µs) is stamped ``clock.host_time_s(t)`` (the
receiver's board clock model, host monotonic seconds) plus the offset of LSL's
``local_clock()`` from the host monotonic clock, measured when the outlets open (liblsl's
clock is the same steady clock on Linux: the offset is about 0). Spikes, PSP samples and
markers are stamped by the model as their events arrive; a decision by the model as it was
when the events of its board time arrived, so it lands in the spike stream where its board
time lies.
"""

from __future__ import annotations

import bisect
import dataclasses
import logging
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from skinhil.errors import ConfigError
from skinhil.lsl.metadata import (
    add_plain_channels,
    add_sensor_channels,
    add_sensor_table,
    describe,
)
from skinhil.model.geometry import Mesh
from skinhil.receiver import (
    LinkReport,
    Receiver,
    ReceiverListener,
    ScoredDecision,
    in_stream_order,
)
from skinhil.receiver.traces import PspTraces

log = logging.getLogger(__name__)

PUSH_PERIOD_US = 20_000
"""Board time (µs) between pushes: spikes and PSP samples go out in chunks of 20 ms (LSL
consumers see them that much later, stamped at their board time all the same)."""

READS_KEPT = 4096
"""Recent reads whose clock offsets decisions are stamped by (a few seconds of reads)."""

MAX_SPIKES_PER_PUSH = 50_000
"""Spikes kept before a push whatever the board time."""

LINGER_S = 0.5
"""Seconds the outlets stay open after the last push while consumers are connected: liblsl
sends from threads of its own, and an outlet destroyed right after a push drops what they
have not sent yet (seen: the last 10 of 1,717 spikes, in 1 of 4 runs of tests/test_lsl.py)."""


LINK_CHANNELS = tuple(f.name for f in dataclasses.fields(LinkReport)) + (
    "board_late_ticks", "board_events_queued", "board_running")
"""The link stream's channels: the receiver's :class:`LinkReport` counters (counts since it
started), then the board's late ticks and queued events as of its last STATUS and whether
it runs (1/0)."""


def require_pylsl() -> None:
    """Raise :class:`ConfigError` (one line, the pip command) when pylsl is not installed."""
    try:
        import pylsl  # noqa: F401
    except ImportError:
        raise ConfigError('LSL outlets need pylsl, which is not installed: '
                          'pip install "skinhil[lsl]"') from None


def _stream(name: str, kind: str, channels: int, rate_hz: float, fmt: Any,
            source: str, provenance: Mapping[str, str]) -> Any:
    import pylsl

    info = pylsl.StreamInfo(name, kind, channels, rate_hz, fmt, source)
    info.desc().append_child_value("manufacturer", "skinhil")
    describe(info, provenance)
    return info


class LslOutlets(ReceiverListener):
    """A receiver listener that publishes its stream as five LSL outlets (see the module);
    ``provenance``: what the streams' desc says of the run (:mod:`skinhil.lsl.metadata`)."""

    def __init__(self, receiver: Receiver, mesh: Mesh, names: dict[int, str],
                 name: str = "skinhil", psp_sensors: Sequence[int] | None = None,
                 provenance: Mapping[str, str] | None = None) -> None:
        require_pylsl()
        import pylsl

        self.receiver = receiver
        self.names = names
        n = int(mesh.springs.shape[0])
        chosen = list(range(n)) if psp_sensors is None else [int(s) for s in psp_sensors]
        self.traces = PspTraces(chosen, n)
        self.lsl_offset_s = pylsl.local_clock() - time.monotonic()
        """LSL clock minus host monotonic clock (s)."""
        self.spikes_pushed = 0
        self._spikes: list[tuple[np.ndarray, np.ndarray]] = []
        self._spikes_n = 0
        self._last_event_us = -1
        self._last_known_us = -1
        """Newest board time (µs) before which the stream is complete (events, STATUS)."""
        self._pushed_us = -1
        self._read_ends_us: list[int] = []
        """Board time (µs) of the newest event of each recent read, increasing."""
        self._read_offsets_s: list[float] = []
        """The clock model's offset (s) when each of those reads arrived."""

        prov = {"size": f"{mesh.size[0]}x{mesh.size[1]}", "sensors": str(n),
                **(provenance or {})}
        spikes = _stream(f"{name}-spikes", "Spikes", 1, pylsl.IRREGULAR_RATE, "int32",
                         f"skinhil:{name}:spikes", prov)
        add_plain_channels(spikes, [("sensor", "address", "SpikeAddress")])
        add_sensor_table(spikes, mesh)
        psp = _stream(f"{name}-psp", "PSP", len(chosen), self.traces.rate_hz, "float32",
                      f"skinhil:{name}:psp", prov)
        add_sensor_channels(psp, mesh, chosen, "a.u.", "PSP")
        markers = _stream(f"{name}-markers", "Markers", 1, pylsl.IRREGULAR_RATE, "string",
                          f"skinhil:{name}:markers", prov)
        add_plain_channels(markers, [("ground truth", "", "Marker")])
        decisions = _stream(f"{name}-decisions", "Markers", 1, pylsl.IRREGULAR_RATE,
                            "string", f"skinhil:{name}:decisions", prov)
        add_plain_channels(decisions, [("decision", "", "Marker")])
        link = _stream(f"{name}-link", "LinkHealth", len(LINK_CHANNELS),
                       pylsl.IRREGULAR_RATE, "double64", f"skinhil:{name}:link", prov)
        add_plain_channels(link, [(c, "" if c == "board_running" else "count", "Counter")
                                  for c in LINK_CHANNELS])
        self.outlets = {key: pylsl.StreamOutlet(info) for key, info in (
            ("spikes", spikes), ("psp", psp), ("markers", markers), ("decisions", decisions),
            ("link", link))}

    def lsl_time_s(self, board_t_us: int | np.ndarray) -> Any:
        """LSL clock time (s) of board time ``board_t_us`` (µs) by the receiver's clock model
        now."""
        offset = self.receiver.clock.offset_s
        return np.asarray(board_t_us) * 1e-6 + offset + self.lsl_offset_s

    def _stamp_as_received(self, board_t_us: int) -> float:
        """LSL time of ``board_t_us`` by the clock model as it was when the events of that
        board time arrived (the spikes' stamps): a decision, made a window later, lands
        where its board time lies in the spike stream even if the model moved since."""
        i = bisect.bisect_left(self._read_ends_us, board_t_us)
        if i == len(self._read_ends_us):
            return float(self.lsl_time_s(board_t_us))
        return board_t_us * 1e-6 + self._read_offsets_s[i] + self.lsl_offset_s

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        if events.shape[0] == 0:
            return
        self._spikes.append((events["addr"].astype(np.int32), self.lsl_time_s(events["t"])))
        self._read_ends_us.append(int(events["t"][-1]))
        self._read_offsets_s.append(self.receiver.clock.offset_s)
        if len(self._read_ends_us) > 2 * READS_KEPT:
            del self._read_ends_us[:READS_KEPT], self._read_offsets_s[:READS_KEPT]
        self._spikes_n += int(events.shape[0])
        self.traces.add(events)
        self._last_event_us = int(events["t"][-1])
        self._last_known_us = max(self._last_known_us, self._last_event_us)
        if self._spikes_n >= MAX_SPIKES_PER_PUSH or \
                self._last_event_us - self._pushed_us >= PUSH_PERIOD_US:
            self._push(self._last_event_us)

    def _push(self, board_t_us: int, final: bool = False) -> None:
        """Push the spikes kept so far and the PSP samples up to ``board_t_us`` (µs)."""
        if self._spikes:
            addr = np.concatenate([a for a, _ in self._spikes]).reshape(-1, 1)
            stamps = np.concatenate([s for _, s in self._spikes])
            self.outlets["spikes"].push_chunk(addr, stamps.tolist())
            self.spikes_pushed += int(addr.shape[0])
            self._spikes, self._spikes_n = [], 0
        self._pushed_us = board_t_us
        first, values = self.traces.advance(board_t_us, final)
        if values.shape[0]:
            last_us = (first + values.shape[0] - 1) * self.traces.sample_us
            self.outlets["psp"].push_chunk(values, float(self.lsl_time_s(last_us)))

    def on_status(self, status: Any) -> None:
        if in_stream_order(status) and int(status.t_us) > self._last_known_us:
            self._last_known_us = int(status.t_us)
            self._push(self._last_known_us)
        self._push_link(int(status.t_us))

    def _push_link(self, board_t_us: int) -> None:
        """One link-health sample, stamped at ``board_t_us`` (µs)."""
        if not self.receiver.clock.synced:
            return
        report = self.receiver.link_report().as_dict()
        st = self.receiver.last_status
        values = [float(report[c]) for c in LINK_CHANNELS[:len(report)]] + [
            float(getattr(st, "late_ticks", 0) or 0),
            float(getattr(st, "events_queued", 0) or 0),
            1.0 if getattr(st, "running", False) else 0.0]
        self.outlets["link"].push_sample(values, float(self.lsl_time_s(board_t_us)))

    def on_marker(self, marker: Any) -> None:
        phase = getattr(marker.phase, "name", str(marker.phase)).lower()
        sid = int(marker.stimulus_id)
        text = (f"{phase} {sid} {self.names.get(sid, str(sid))} "
                f"t_board_s={int(marker.t_us) * 1e-6:.4f}")
        self.outlets["markers"].push_sample([text], float(self.lsl_time_s(int(marker.t_us))))

    def on_decision(self, decision: ScoredDecision) -> None:
        p = decision.prediction
        verdict = {True: "correct", False: "wrong", None: "no-marker"}[decision.correct]
        truth = "-" if decision.true_label is None else str(decision.true_label)
        text = (f"decision {p.label} {self.names.get(p.label, str(p.label))} true={truth} "
                f"{verdict} t_board_s={p.decided_t_us * 1e-6:.4f}")
        self.outlets["decisions"].push_sample([text], self._stamp_as_received(p.decided_t_us))

    def close(self) -> None:
        """Push what is kept, then close the outlets (LSL consumers see the streams end),
        :data:`LINGER_S` after the last push while anyone reads them."""
        if self._last_known_us >= 0:
            self._push(max(self._last_known_us, self._last_event_us + self.traces.sample_us),
                       final=True)
            self._push_link(self._last_known_us)
        if any(outlet.have_consumers() for outlet in self.outlets.values()):
            time.sleep(LINGER_S)
        self.outlets.clear()
