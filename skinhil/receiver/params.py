"""Parameters of the online receiver: onset detection, decision window, board-time guard."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from skinhil.validation import Constraints, InstanceOf, non_negative, positive, validate_params


@dataclass(frozen=True)
class OnsetParams:
    """The activity-only stimulus-onset rule (see :mod:`skinhil.receiver.onset`).

    ``window_s`` (s): length of the sliding window in which the population's spikes are
    counted. ``z``: how many baseline standard deviations above the baseline mean the count
    must rise, and ``min_excess_spikes`` the least excess (spikes) in any case, so a silent
    (noise-free) baseline still needs that many spikes. ``baseline_tau_s`` (s): time constant
    of the running baseline; ``warmup_s`` (s): baseline-only time after the stream starts.
    ``refractory_s`` (s): no new onset this soon after one (stimuli are further apart).
    ``lookback_s`` (s): the decision window starts this long before the detection step, to
    cover the first spikes the window count needed (median detection delay without noise).
    """

    window_s: float = 0.005
    z: float = 4.0
    min_excess_spikes: float = 3.0
    baseline_tau_s: float = 0.5
    warmup_s: float = 0.05
    refractory_s: float = 0.2
    lookback_s: float = 0.003

    _parameter_constraints: ClassVar[Constraints] = {
        "window_s": positive("s"),
        "z": non_negative("baseline standard deviations"),
        "min_excess_spikes": non_negative("spikes"),
        "baseline_tau_s": positive("s"),
        "warmup_s": non_negative("s"),
        "refractory_s": positive("s"),
        "lookback_s": non_negative("s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)


@dataclass(frozen=True)
class ReceiverParams:
    """How the receiver follows board time and scores its decisions.

    ``guard_s`` (s): the receiver steps its filters only up to the board time it knows is
    complete: the newest event's time, else the newest record's or the host clock's estimate
    of board time minus this guard (events that still arrive for earlier steps are counted
    as late and applied at the current step). When late events arrive, the guard grows to
    twice the largest lateness seen, up to ``max_guard_s`` (s), so a board that lags behind
    real time (a loaded host) is followed without shifting spikes. ``match_window_s`` (s):
    a decision is scored against the ground-truth marker whose onset precedes its decision
    time by at most this plus the decision window (an onset detected at most this after the
    marker; :mod:`skinhil.receiver.scoring`). ``silence_s`` (s): only a stream silent this
    long is taken as a board that stopped sending (gone, or stalled for good), and then the
    host clock's estimate of board time (minus the guard) moves board time on, so the
    decisions it owes are made.
    The board sends a status every 0.1 s of its time (``BoardConfig.status_period_s``), so a
    shorter silence is a board or link that paused (a loaded host; inside user-mode Linux
    pauses of 50-160 ms were seen): moving on then would make the events after the pause
    late.
    """

    onset: OnsetParams = field(default_factory=OnsetParams)
    guard_s: float = 0.02
    max_guard_s: float = 0.25
    match_window_s: float = 0.1
    silence_s: float = 1.0

    _parameter_constraints: ClassVar[Constraints] = {
        "onset": InstanceOf(OnsetParams, "an OnsetParams"),
        "guard_s": positive("s"),
        "silence_s": positive("s"),
        "max_guard_s": positive("s"),
        "match_window_s": positive("s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)
