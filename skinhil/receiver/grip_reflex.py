"""The reference grip controller: the object's load read from the spikes, the grip kept above
it, and a reflex step when the reading jumps (the baseline a decoder that grips is compared
with; docs/grasp.md "The reference controller").

It reads nothing but the events (their board times and channels). Per bin of ``bin_s`` each
channel's spike count enters an exponential mean of time constant ``tau_s`` (its rate,
spikes/s); a linear readout (:class:`LoadReadout`, fitted offline on simulated lifts,
:mod:`skinhil.receiver.grip_training`) turns the rates into a load estimate ``L̂`` (N). The
grip it asks is

    G = clip(ratio · L̂, low_grip_n, max_grip_n)

and, when ``L̂`` rose by more than ``reflex_n`` within ``reflex_s`` (a load coming on, an
edge slipping), ``reflex_step_n`` more for ``hold_s``. A new grip goes to the board as a GRIP
(SPEC.md §3.5.6) when it differs from the last one sent by ``deadband_n`` or more, never by
more than 90 % of what the board's rate bound allows in one tick (so that GRIPs the link
bunches into one tick pass too) up, and at most ``release_n_per_s`` down.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

import protocols
from skinhil.errors import ConfigError
from skinhil.receiver.answer import CommandSender
from skinhil.transports import Transport
from skinhil.validation import Constraints, positive, validate_params

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ReflexParams:
    """The controller's constants (module docstring); times in s, forces in N."""

    low_grip_n: float = 0.3
    max_grip_n: float = 1.65
    """Below the lowest break force of a sturdy object (tactile-v1: 1.7 N)."""
    ratio: float = 1.4
    """Grip per newton of load read: the slip ratio 1.25 (friction coefficient 0.8) with a
    12 % safety margin (a human hand keeps 10-40 %)."""
    bin_s: float = 0.002
    tau_s: float = 0.03
    reflex_n: float = 0.15
    reflex_s: float = 0.02
    reflex_step_n: float = 0.05
    hold_s: float = 0.1
    deadband_n: float = 0.04
    release_n_per_s: float = 5.0
    """The grip comes down at most this fast (N/s) with the hand empty (a load read below
    ``empty_n``)."""
    hold_release_n_per_s: float = 1.0
    """The grip comes down at most this fast (N/s) while it holds a load: a dip of the
    reading does not let go."""
    empty_n: float = 0.1
    """A load read below this (N) is an empty hand."""
    max_rate_n_per_s: float = 100.0
    """The board's rate bound (SPEC.md §3.5.6): no GRIP asks more."""

    _parameter_constraints: ClassVar[Constraints] = {
        "low_grip_n": positive("N"),
        "max_grip_n": positive("N"),
        "ratio": positive("N of grip per N of load"),
        "bin_s": positive("s"),
        "tau_s": positive("s"),
        "reflex_n": positive("N"),
        "reflex_s": positive("s"),
        "reflex_step_n": positive("N"),
        "hold_s": positive("s"),
        "deadband_n": positive("N"),
        "release_n_per_s": positive("N/s"),
        "hold_release_n_per_s": positive("N/s"),
        "empty_n": positive("N"),
        "max_rate_n_per_s": positive("N/s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)


class ChannelRates:
    """Each channel's spike rate (spikes/s): an exponential mean of time constant ``tau_s``
    of its count per bin of ``bin_s``, closed as events of later bins arrive."""

    def __init__(self, n_channels: int, bin_s: float, tau_s: float) -> None:
        self.bin_us = int(round(bin_s * 1e6))
        self.rates = np.zeros(n_channels)
        self._count = np.zeros(n_channels)
        self._alpha = 1 - math.exp(-bin_s / tau_s)
        self._scale = 1.0 / bin_s
        self._bin = -1

    def bins(self, events: np.ndarray) -> Any:
        """Yield the end time (µs) of each bin that ``events`` close, :attr:`rates` then
        holding that bin's rates."""
        if not len(events):
            return
        bins = events["t"].astype(np.int64) // self.bin_us
        if self._bin < 0:
            self._bin = int(bins[0])
        start = 0
        addr = events["addr"].astype(np.int64)
        for b in np.unique(bins).tolist():
            while self._bin < b:
                self._close()
                yield self._bin * self.bin_us
            stop = int(np.searchsorted(bins, b, side="right"))
            np.add.at(self._count, addr[start:stop], 1.0)
            start = stop

    def _close(self) -> None:
        self.rates += self._alpha * (self._count * self._scale - self.rates)
        self._count[:] = 0.0
        self._bin += 1


@dataclass(frozen=True)
class LoadReadout:
    """A linear load estimate (N) from the channels' rates and the grip the controller
    asks: ``rates @ weights + grip_weight * grip_n + bias``. The grip term is the
    controller's own command (an efference copy, never the board's truth): the skin's rates
    rise with the grip as with the load, and it takes the grip's share out of the reading,
    so that a firmer grip does not read as a heavier object."""

    weights: np.ndarray
    bias: float
    tau_s: float
    bin_s: float
    grip_weight: float = 0.0
    """N of load per N of grip asked."""

    def estimate(self, rates: np.ndarray, grip_n: float = 0.0) -> float:
        """The load (N) the rates (spikes/s) say at the grip ``grip_n`` (N) asked."""
        return float(rates @ self.weights) + self.grip_weight * grip_n + self.bias

    def save(self, path: Path) -> None:
        """Write it as plain data (npz)."""
        np.savez(path, weights=self.weights, bias=self.bias, tau_s=self.tau_s,
                 bin_s=self.bin_s, grip_weight=self.grip_weight)

    @staticmethod
    def load(path: Path, n_channels: int) -> LoadReadout:
        """Read one written by :meth:`save`, for ``n_channels`` channels."""
        try:
            with np.load(path, allow_pickle=False) as z:
                out = LoadReadout(np.asarray(z["weights"], dtype=np.float64),
                                  float(z["bias"]), float(z["tau_s"]), float(z["bin_s"]),
                                  float(z["grip_weight"]) if "grip_weight" in z else 0.0)
        except (OSError, KeyError, ValueError) as exc:
            raise ConfigError(f"'{path}' is not a grip readout ({exc}): delete it to fit "
                              "it again") from None
        if out.weights.shape != (n_channels,):
            raise ConfigError(f"'{path}' reads {out.weights.shape} channels, the board has "
                              f"{n_channels}: delete it to fit it again")
        return out


class SlipReflex:
    """The controller's state (module docstring), fed events; :meth:`feed` returns the grips
    (N) to send, each with the board time (µs) of the bin that asked for it."""

    def __init__(self, readout: LoadReadout, params: ReflexParams | None = None) -> None:
        self.params = params or ReflexParams()
        self.readout = readout
        self.rates = ChannelRates(len(readout.weights), readout.bin_s, readout.tau_s)
        self.grip_n = self.params.low_grip_n
        self.load_n = 0.0
        """The last load estimate (N)."""
        self._recent: deque[tuple[int, float]] = deque()
        self._reflex_until_us = -1

    def feed(self, events: np.ndarray) -> list[tuple[int, float]]:
        """Account ``events`` (``t`` µs, ``addr``; in time order); the grips to send now."""
        p = self.params
        out: list[tuple[int, float]] = []
        for t_us in self.rates.bins(events):
            load = self.readout.estimate(self.rates.rates, self.grip_n)
            self.load_n = load
            recent = self._recent
            recent.append((t_us, load))
            while recent and recent[0][0] < t_us - p.reflex_s * 1e6:
                recent.popleft()
            if load - min(v for _, v in recent) > p.reflex_n:
                self._reflex_until_us = t_us + int(p.hold_s * 1e6)
            want = p.ratio * load
            if t_us < self._reflex_until_us:
                want += p.reflex_step_n
            want = min(max(want, p.low_grip_n), p.max_grip_n)
            if abs(want - self.grip_n) < p.deadband_n:
                continue
            room = p.max_rate_n_per_s * 1e-3 * 0.9  # one tick's worth: bunched GRIPs pass
            release = p.release_n_per_s if load < p.empty_n else p.hold_release_n_per_s
            step = max(-release * p.bin_s, min(room, want - self.grip_n))
            self.grip_n = round(self.grip_n + step, 6)
            out.append((t_us, self.grip_n))
        return out


class GripController(CommandSender):
    """Sends the reflex's grips to the board on ``transport`` (board ``board_id``) as GRIP
    commands (SPEC.md §3.5.3), and counts the board's answers."""

    def __init__(self, transport: Transport[Any], reflex: SlipReflex, board_id: int = 0) -> None:
        super().__init__(transport, board_id)
        self.reflex = reflex
        self._token = 0
        self.grips: list[tuple[int, int, float]] = []
        """(token, board time µs of the bin that asked, grip N) of each GRIP sent."""

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        for t_us, grip in self.reflex.feed(events):
            self._token = (self._token + 1) % 65536
            command = protocols.Command(self._token, protocols.CommandCode.GRIP, grip)
            if self.send(command, f"GRIP of {grip:g} N"):
                self.grips.append((self._token, int(t_us), grip))

    def on_ack(self, ack: Any) -> None:
        if ack.opcode == protocols.CommandCode.GRIP:
            self.count_ack(ack)
