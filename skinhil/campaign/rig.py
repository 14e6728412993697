"""Faults of the rig, apart from failures of the decoder under test.

The board's health comes from ``serve --json``'s final ``summary`` line, the one place it
reports the run whole (``firmware_sim.board.BoardSummary``): ticks late beyond a bound
(``lateness_ms.max``, ``deadline_misses``), events the board dropped on its side
(``dropped_by``: ``fifo_full``, ``link_down``, ``shutdown``) and link losses
(``link_losses``: the link went away and was reopened). On the bench's own link
(:mod:`skinhil.campaign.relay`) a tap also decodes the board's stream on its way to the
decoder and counts damaged or missing frames (CRC errors, malformed frames, frames lost by
the sequence numbers). Past its bound each is a fault of the rig: the case is an error, the
decoder's criteria are not held against it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from numbers import Integral
from typing import Any, ClassVar

from skinhil.model.schedule_file import checked_table
from skinhil.validation import Constraints, Interval, check_param, positive, validate_params

RIG_KEYS = ("max_lateness_ms", "max_deadline_misses", "max_fifo_drops", "max_link_losses",
            "max_link_errors", "timeout_s")


_COUNT = Interval(Integral, 0, None, closed="left", unit="count")


@dataclass(frozen=True)
class RigBounds:
    """What the rig may show before a case is its error (counts per case)."""

    max_lateness_ms: float = 50.0
    """Latest tick (ms behind its deadline) the board may have."""
    max_deadline_misses: int | None = None
    """Ticks that may miss their deadline at all (None: any number; a loaded machine misses
    many by a fraction of a millisecond)."""
    max_fifo_drops: int = 0
    """Events the board may drop on its side (FIFO full, link down, shutdown)."""
    max_link_losses: int = 0
    """Times the link may go away (and be reopened)."""
    max_link_errors: int = 0
    """Frames the bench's link tap may see damaged or missing (its own link only)."""
    timeout_s: float = 120.0
    """Wall time (s) a case may take beyond its board time (start-up, compile, drain)."""

    _parameter_constraints: ClassVar[Constraints] = {
        "max_lateness_ms": positive("ms"),
        "max_deadline_misses": [_COUNT, None],
        "max_fifo_drops": _COUNT,
        "max_link_losses": _COUNT,
        "max_link_errors": _COUNT,
        "timeout_s": positive("s"),
    }

    def __post_init__(self) -> None:
        validate_params(self)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def rig_bounds_from_table(table: object, where: str) -> RigBounds:
    """The ``[rig]`` table as :class:`RigBounds`, else a one-line :class:`ConfigError`."""
    t = checked_table(table, RIG_KEYS, where)
    default = RigBounds()
    values: dict[str, Any] = {}
    for key, raw in t.items():
        check_param(key, raw, RigBounds._parameter_constraints[key], where=f"{where}: ")
        number: Any = raw
        values[key] = float(number) if isinstance(getattr(default, key), float) else number
    return RigBounds(**values)


BOARD_DROPS = ("fifo_full", "link_down", "shutdown")
"""The board's drop reasons that are the rig's (``stopped`` is a STOP command's)."""
TAP_ERRORS = ("crc_errors", "malformed", "frames_lost")
"""The link tap's counters (:class:`protocols.records.LinkCounters`) that are faults."""


def board_health(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The rig's figures of ``serve --json``'s summary line."""
    return {"lateness_max_ms": float(summary["lateness_ms"]["max"]),
            "deadline_misses": int(summary["deadline_misses"]),
            "ticks": int(summary["ticks"]),
            "fifo_drops": sum(int(summary["dropped_by"].get(k, 0)) for k in BOARD_DROPS),
            "link_losses": int(summary["link_losses"]),
            "commands": int(summary["commands"])}


def rig_faults(bounds: RigBounds, board: Mapping[str, Any] | None,
               tap: Mapping[str, int] | None) -> list[str]:
    """Each fault of the rig, one line each, from :func:`board_health`'s figures and the
    link tap's counters (None: no tap)."""
    faults = []
    if board is not None:
        if board["lateness_max_ms"] > bounds.max_lateness_ms:
            faults.append(f"a tick {board['lateness_max_ms']:.1f} ms late (bound "
                          f"{bounds.max_lateness_ms:g} ms)")
        if bounds.max_deadline_misses is not None and \
                board["deadline_misses"] > bounds.max_deadline_misses:
            faults.append(f"{board['deadline_misses']} of {board['ticks']} ticks missed "
                          f"their deadline (bound {bounds.max_deadline_misses})")
        if board["fifo_drops"] > bounds.max_fifo_drops:
            faults.append(f"the board dropped {board['fifo_drops']} events (bound "
                          f"{bounds.max_fifo_drops})")
        if board["link_losses"] > bounds.max_link_losses:
            faults.append(f"the link went away {board['link_losses']} times (bound "
                          f"{bounds.max_link_losses})")
    if tap is not None:
        faults += _tap_faults(bounds, tap)
    return faults


def _tap_faults(bounds: RigBounds, tap: Mapping[str, Any]) -> list[str]:
    """The link tap's faults: frames damaged or missing by the sequence numbers, and with
    injected faults (``tap["injected"]``) the frames dropped or held back past the run's
    end, which no sequence gap shows when they are the last (or all) of the run."""
    injected = tap.get("injected")
    undelivered = (int(injected["dropped"]) + int(injected.get("held_at_end", 0))
                   if injected else 0)
    bad = (int(tap["crc_errors"]) + int(tap["malformed"])
           + max(int(tap["frames_lost"]), undelivered))
    faults = []
    if injected and int(injected["units_seen"]) > 0 and int(tap["frames_ok"]) == 0:
        faults.append(f"the decoder received nothing: the board sent {injected['units_seen']} "
                      "frames and none reached it whole (injected faults)")
    if bad > bounds.max_link_errors:
        detail = ", ".join(f"{tap[k]} {k.replace('_', ' ')}" for k in TAP_ERRORS)
        if injected:
            detail += (f"; injected: {injected['dropped']} dropped, "
                       f"{injected.get('held_at_end', 0)} delayed beyond the run")
        faults.append(f"the link damaged or lost {bad} frames on the way to the decoder "
                      f"({detail}; bound {bounds.max_link_errors})")
    return faults
