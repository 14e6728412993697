"""Golden sessions: a board played tick by tick, off the clock, over an in-memory link of
unlimited rate, with host commands at scripted ticks; what it hands the link is the capture.

Nothing in such a session depends on the machine or on time: the link takes every unit at
once (pacing never binds), the ticks are stepped by hand (no deadline is missed), the host's
commands arrive at fixed ticks. So a change that keeps the board's behaviour keeps every
byte (``tests/test_golden_sessions.py``); ``python tests/harness/golden.py`` records the
captures again, which a change of behaviour must do on purpose, and say so.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import protocols
from firmware_sim.board import Board, BoardConfig
from skinhil.model.timeline import Timeline
from skinhil.plant import GraspParams, lift_scene
from skinhil.plant.report import plant_scores
from skinhil.transports.base import Transport
from skinhil.world.scenario_file import load_scenario

GOLDEN_DIR = Path(__file__).resolve().parents[1] / "golden"
EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
UNIT_WIRE_S = 1e-12
"""Wire time (s) of one byte or frame on the golden link: the budget never binds."""


class GoldenLink(Transport[Any]):
    """An in-memory link of unlimited rate: keeps every unit the board sends; hands the board
    the host's units scheduled for the current tick (:attr:`tick`, set by the player)."""

    scheme = "golden"

    def __init__(self, frames: bool, can_fd: bool = False) -> None:
        self.kind = "can" if frames else "serial"
        self.carries_frames = frames
        self.unit = "frames" if frames else "bytes"
        self.can_fd = can_fd
        self.script: dict[int, list[Any]] = {}
        """The host's units by the tick they arrive at."""
        self.tick = -1
        self.units: list[Any] = []

    @property
    def name(self) -> str:
        return f"golden-{self.unit}"

    def send(self, payload: Any, timeout: float | None = None) -> int:
        if self.carries_frames:
            self.units.extend(payload)
        else:
            self.units.append(bytes(payload))
        return len(payload)

    def recv(self, timeout: float | None = None) -> Any:
        due = [k for k in self.script if k <= self.tick]
        out: list[Any] = []
        for k in sorted(due):
            for unit in self.script.pop(k):
                out.extend(unit) if self.carries_frames else out.append(unit)
        if self.carries_frames:
            return out
        return b"".join(out)

    def wire_seconds(self, payload: Any) -> float:
        return len(payload) * UNIT_WIRE_S

    def empty(self) -> Any:
        return [] if self.carries_frames else b""

    def shutdown(self) -> None:
        pass


def capture_bytes(link: GoldenLink) -> bytes:
    """The units a board sent, as one byte string: a serial stream as it is; CAN frames one
    after another as id (u16 LE), FD flag (u8), length (u8), data."""
    if not link.carries_frames:
        return b"".join(link.units)
    out = bytearray()
    for f in link.units:
        out += int(f.arbitration_id).to_bytes(2, "little") + bytes([int(f.is_fd), len(f.data)])
        out += bytes(f.data)
    return bytes(out)


@dataclass
class Session:
    """One golden session: how the board is made, what the host sends when, how long."""

    name: str
    frames: bool
    ticks: int
    config: BoardConfig
    commands: dict[int, list[Any]]
    fd: bool = False
    board_args: Callable[[], dict[str, Any]] = field(default=lambda: {})


def _host_script(link: GoldenLink, board_id: int,
                 commands: dict[int, list[Any]]) -> dict[int, list[Any]]:
    """The host's commands encoded as a host sends them on ``link`` (its own sequence
    numbers)."""
    enc = link.codec_pair(board_id=board_id)[0]
    return {k: [enc.command(c) for c in cmds] for k, cmds in commands.items()}


def _common_commands() -> dict[int, list[Any]]:
    C, op, T = protocols.Command, protocols.CommandCode, protocols.Task
    return {
        50: [C(1, op.QUERY_STATUS), C(2, op.PING)],
        120: [protocols.Decision(3, 2, 0.8)],
        121: [protocols.Decision(4, 2, 0.5), protocols.Decision(5, 77, None)],
        200: [C(6, op.SET_SNR, 20.0)],
        260: [protocols.Answer(7, T.CLASSIFICATION, (1.0,)),
              protocols.Answer(8, T.FORCE, (0.3,))],
        300: [C(9, op.STOP)],
        420: [C(10, op.START), C(11, op.QUERY_SESSION)],
        500: [C(12, op.SET_STIMULUS, 3)],
        650: [C(13, 99), C(14, op.SET_SNR, -500.0), C(15, op.GRIP, 1.0)],
        800: [C(16, op.SET_SCHEDULE, 1)],
        1100: [C(17, op.QUERY_STATUS)],
    }


def _answers() -> dict[int, list[Any]]:
    """ANSWERs to a contact scenario: every task at a fixed cadence, some right, most not."""
    T = protocols.Task
    out: dict[int, list[Any]] = {}
    token = 100
    for k in range(130, 4000, 97):
        token += 3
        out[k] = [protocols.Answer(token, T.LOCALISATION, (0.01 * (k % 200) - 1.0, 0.0)),
                  protocols.Answer(token + 1, T.FORCE, (1.0 if k % 2 else 0.4,)),
                  protocols.Answer(token + 2, T.SLIP, ())]
    out[4001] = [protocols.Answer(9000, T.VIBRATION, (100.0,)),
                 protocols.Answer(9001, 13, (0.0,))]
    return out


def _grips() -> dict[int, list[Any]]:
    """GRIPs to a held object: a steady grip, a rise, one over the limit, a release."""
    C, op = protocols.Command, protocols.CommandCode
    grips = {5: 0.6, 300: 0.9, 310: 1.2, 700: 50.0, 900: 0.4, 1300: 1.1, 1800: -1.0,
             1900: 1e30, 2000: 0.8, 2600: 0.0, 2700: 1.0}
    return {k: [C(200 + i, op.GRIP, g)] for i, (k, g) in enumerate(grips.items())}


def sessions() -> list[Session]:
    """The golden sessions: serial, CAN FD, a scored contact scenario, a held object."""
    serial = BoardConfig(seed=3, snr_db=10.0, schedule_mode=Timeline.SCHEDULE_RANDOM)
    can = BoardConfig(seed=4, snr_db=10.0, board_id=2, schedule_mode=Timeline.SCHEDULE_RANDOM)
    contact = BoardConfig(seed=5, snr_db=10.0, schedule_mode=Timeline.SCHEDULE_FILE,
                          markers=False)
    grasp = BoardConfig(seed=6, snr_db=10.0, schedule_mode=Timeline.SCHEDULE_FILE,
                        markers=False)

    def scenario() -> dict[str, Any]:
        s = load_scenario(EXAMPLES / "task_slip.toml", contact.size)
        return {"file_schedule": s.schedule, "scene": s.scene}

    def held() -> dict[str, Any]:
        params = GraspParams()
        return {"scene": lift_scene(params, 2), "grasp": params}

    return [
        Session("serial", False, 1500, serial, _common_commands()),
        Session("can_fd", True, 1500, can, _common_commands(), fd=True),
        Session("contact_answers", False, 4200, contact, _answers(), board_args=scenario),
        Session("grasp_grips", True, 3000, grasp, _grips(), fd=False, board_args=held),
    ]


def play(session: Session) -> tuple[bytes, dict[str, Any]]:
    """Play ``session``: the capture (:func:`capture_bytes`) and the board's scores."""
    link = GoldenLink(session.frames, can_fd=session.fd)
    link.script = _host_script(link, session.config.board_id, session.commands)
    board = Board(session.config, lambda: link, **session.board_args())
    board.warm_up()
    assert board.link is not None
    board.queue_session(protocols.SessionReason.START)
    for k in range(session.ticks):
        link.tick = k
        board.tick()
    board.finish(protocols.RunEndReason.DURATION)
    summary = board.summary()
    scores: dict[str, Any] = {"generated": summary.generated, "sent": summary.sent,
                              "dropped_by": summary.dropped_by, "commands": summary.commands,
                              "nacks": summary.nacks, "scoreboard": summary.scoreboard,
                              "tasks": summary.tasks}
    if board.plant is not None:
        scores["grasp"] = plant_scores(board.plant, board.truth)
    return capture_bytes(link), json.loads(json.dumps(scores, default=_plain))


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON")


def record(names: list[str] | None = None) -> None:
    """Record the golden captures (all, or those named) into :data:`GOLDEN_DIR`."""
    GOLDEN_DIR.mkdir(exist_ok=True)
    for s in sessions():
        if names and s.name not in names:
            continue
        data, scores = play(s)
        (GOLDEN_DIR / f"{s.name}.bin").write_bytes(data)
        (GOLDEN_DIR / f"{s.name}.json").write_text(
            json.dumps(scores, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"{s.name}: {len(data)} bytes, sha256 {hashlib.sha256(data).hexdigest()[:16]}")


if __name__ == "__main__":
    record(sys.argv[1:])
