"""The LSL outlets of one receiver: spikes, PSP traces, ground-truth markers, decisions.

Four streams, named ``NAME-spikes``, ``NAME-psp``, ``NAME-markers``, ``NAME-decisions``
(source ids ``skinhil:NAME:...``, so a recorder that loses them finds them again):

- **spikes** (type ``Spikes``, irregular rate, one ``int32`` channel): one sample per
  spike, its value the sensor (spring) address, stamped at the spike's board time;
- **psp** (type ``PSP``, 1 kHz, one ``float32`` channel per chosen sensor): the eq. 12 PSP
  of each sensor (dimensionless, a spike's kernel peaks at ≈1), stamped at board time;
- **markers** (type ``Markers``, irregular, one string channel): each ground-truth marker
  as ``onset 3 120deg_0.5N t_board_s=12.3456``;
- **decisions** (type ``Markers``, irregular, one string channel): each online decision as
  ``decision 3 120deg_0.5N true=3 correct t_board_s=12.3456`` (board time of the decision).

Every stream's ``desc`` holds the channel labels and units LSL tools read: for the psp
stream one ``channel`` per sensor (``label`` ``S12 M8-M9``, ``unit`` ``a.u.``, ``type``
``PSP``, the spring and its two masses), for the spikes stream the sensor table
(``sensors/sensor``: address and the spring's two masses) and the ``unit`` of the value
(``address``).

Spikes and PSP samples are pushed in chunks of :data:`PUSH_PERIOD_US` of board time (and
whatever is left when the outlets close), markers and decisions at once.

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
import logging
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.geometry import Mesh
from skinhil.receiver import Receiver, ReceiverListener, ScoredDecision
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


def require_pylsl() -> None:
    """Raise :class:`ConfigError` (one line, the pip command) when pylsl is not installed."""
    try:
        import pylsl  # noqa: F401
    except ImportError:
        raise ConfigError('LSL outlets need pylsl, which is not installed: '
                          'pip install "skinhil[lsl]"') from None


def sensor_label(mesh: Mesh, address: int) -> str:
    """``S12 M8-M9``: the sensor's address and the 1-based numbers of its spring's masses."""
    i, j = mesh.springs[address]
    return f"S{address} M{int(i) + 1}-M{int(j) + 1}"


def _stream(name: str, kind: str, channels: int, rate_hz: float, fmt: Any,
            source: str) -> Any:
    import pylsl

    info = pylsl.StreamInfo(name, kind, channels, rate_hz, fmt, source)
    info.desc().append_child_value("manufacturer", "skinhil")
    return info


class LslOutlets(ReceiverListener):
    """A receiver listener that publishes its stream as four LSL outlets (see the module)."""

    def __init__(self, receiver: Receiver, mesh: Mesh, names: dict[int, str],
                 name: str = "skinhil", psp_sensors: Sequence[int] | None = None) -> None:
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
        self._pushed_us = -1
        self._read_ends_us: list[int] = []
        """Board time (µs) of the newest event of each recent read, increasing."""
        self._read_offsets_s: list[float] = []
        """The clock model's offset (s) when each of those reads arrived."""

        spikes = _stream(f"{name}-spikes", "Spikes", 1, pylsl.IRREGULAR_RATE, "int32",
                         f"skinhil:{name}:spikes")
        ch = spikes.desc().append_child("channels").append_child("channel")
        ch.append_child_value("label", "sensor")
        ch.append_child_value("unit", "address")
        ch.append_child_value("type", "SpikeAddress")
        table = spikes.desc().append_child("sensors")
        for a in range(n):
            i, j = mesh.springs[a]
            s = table.append_child("sensor")
            s.append_child_value("address", str(a))
            s.append_child_value("mass_i", f"M{int(i) + 1}")
            s.append_child_value("mass_j", f"M{int(j) + 1}")

        psp = _stream(f"{name}-psp", "PSP", len(chosen), self.traces.rate_hz, "float32",
                      f"skinhil:{name}:psp")
        chans = psp.desc().append_child("channels")
        for a in chosen:
            c = chans.append_child("channel")
            c.append_child_value("label", sensor_label(mesh, a))
            c.append_child_value("unit", "a.u.")
            c.append_child_value("type", "PSP")
            c.append_child_value("sensor", str(a))

        markers = _stream(f"{name}-markers", "Markers", 1, pylsl.IRREGULAR_RATE, "string",
                          f"skinhil:{name}:markers")
        decisions = _stream(f"{name}-decisions", "Markers", 1, pylsl.IRREGULAR_RATE,
                            "string", f"skinhil:{name}:decisions")
        for info, label in ((markers, "ground truth"), (decisions, "decision")):
            c = info.desc().append_child("channels").append_child("channel")
            c.append_child_value("label", label)
            c.append_child_value("type", "Marker")
        self.outlets = {key: pylsl.StreamOutlet(info) for key, info in (
            ("spikes", spikes), ("psp", psp), ("markers", markers), ("decisions", decisions))}

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
        if self._last_event_us >= 0:
            self._push(self._last_event_us + self.traces.sample_us, final=True)
        if any(outlet.have_consumers() for outlet in self.outlets.values()):
            time.sleep(LINGER_S)
        self.outlets.clear()
