"""``skinhil.Board``: the emulated board (:class:`firmware_sim.board.Board`) running in real
time on a background thread, over a link it opens, for a notebook or a script.

The board is built and its kernels warmed in the caller's thread (a cold compile is
announced: :func:`skinhil.kernel_notice.compiling`), then it runs on a thread until its
``duration_s`` of board time, :meth:`Board.close` or the end of the ``with`` block. An
exception raised in that thread is raised again by :meth:`Board.wait` and
:meth:`Board.close`.
"""

from __future__ import annotations

import dataclasses
import threading
from pathlib import Path
from typing import Any

from firmware_sim.board import Board as BoardEmulator
from firmware_sim.config import BoardConfig, BoardSummary
from firmware_sim.score import board_score
from skinhil.api.background import BackgroundRun
from skinhil.api.links import open_api_link
from skinhil.errors import ConfigError
from skinhil.kernel_notice import compiling
from skinhil.model.geometry import MeshSize
from skinhil.model.stimuli import Schedule
from skinhil.model.timeline import Timeline
from skinhil.plant import GraspParams
from skinhil.suites import suite_trials
from skinhil.transports import Transport
from skinhil.world import Scene
from skinhil.world.scenario_file import load_scenario

SUMMARY_NAMES: dict[str, str] = {"generated": "events_generated", "sent": "events_sent",
                                 "dropped": "events_dropped", "queued": "events_queued"}
"""The board summary's event counts under the names of the wire's STATUS fields."""

STOP_TIMEOUT_S = 30.0
"""Longest :meth:`Board.close` waits for the board's thread (s): the drain of the FIFO
onto the link (``BoardConfig.drain_timeout_s``) and the final records."""


class Board(BackgroundRun):
    """The emulated sensor board, in real time on a background thread.

    ``size`` (rows, columns of the top layer), ``snr_db`` (dB; inf: no neuron noise) and
    ``seed`` set the skin and its noise; ``duration_s`` (s of board time; None: until
    :meth:`close`) ends the run. ``link``: None opens a new pty pair, whose other end is
    :attr:`peer` (a serial port's path); else a link URL (``serial:...``, ``can:vcan0``,
    ``udp:HOST:PORT``, ``pty:``; docs/links.md), a serial device path or an open
    :class:`~skinhil.transports.Transport`. What it plays: the seeded random schedule of the
    9 direction conditions, or ``suite`` (``"tactile-v1:localisation"``, drawn from
    ``seed``; its length is the case's unless ``duration_s`` is given) or ``scenario`` (a
    scenario or schedule file). ``options`` are further :class:`BoardConfig` fields
    (``rest_s``, ``tick_s``, ``markers``, ...).
    """

    stop_timeout_s = STOP_TIMEOUT_S

    def __init__(self, size: MeshSize = (6, 6), snr_db: float = 10.0, seed: int = 0,
                 duration_s: float | None = None, *, link: str | Transport[Any] | None = None,
                 suite: str | None = None, scenario: str | Path | None = None,
                 **options: Any) -> None:
        if suite is not None and scenario is not None:
            raise ConfigError("give suite= or scenario=, not both: a suite case is a scenario")
        schedule: Schedule | None = None
        scene: Scene | None = None
        grasp: GraspParams | None = None
        tasks = None
        if suite is not None:
            trials = suite_trials(suite, seed, size)
            schedule, scene, grasp = trials.scenario.schedule, trials.scenario.scene, trials.grasp
            tasks = tuple(t.name for t in trials.tasks)
            duration_s = trials.duration_s if duration_s is None else duration_s
        elif scenario is not None:
            loaded = load_scenario(scenario, size)
            schedule, scene = loaded.schedule, loaded.scene
        mode = Timeline.SCHEDULE_RANDOM if schedule is None else Timeline.SCHEDULE_FILE
        try:
            config = BoardConfig(size=size, snr_db=snr_db, seed=seed, schedule_mode=mode,
                                 **options)
        except TypeError as exc:
            fields = ", ".join(f.name for f in dataclasses.fields(BoardConfig))
            raise ConfigError(f"{exc}: give only BoardConfig's fields ({fields})") from None
        if tasks is not None:
            config = dataclasses.replace(config, tasks=tasks)
        self.duration_s = duration_s
        """Board time (s) the run lasts; None: until :meth:`close`."""
        self.transport: Transport[Any] = open_api_link("pty:" if link is None else link,
                                                       "board")
        self.peer: str | None = getattr(self.transport, "slave_path", None)
        """The path of the pty's other end (a serial port the receiver opens), None on
        other links."""
        self._messages: list[str] = []
        try:
            with compiling("serve"):
                self.emulator = BoardEmulator(config, lambda: self.transport, schedule,
                                              self._messages.append, scene, grasp)
                self.emulator.warm_up()
        except BaseException:
            self.transport.shutdown()
            raise
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._summary: BoardSummary | None = None
        self._thread = threading.Thread(target=self._run, name="skinhil-board", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self._summary = self.emulator.run(self.duration_s, self._stop)
        except BaseException as exc:  # raised again in the caller's thread
            self._error = exc
            self.transport.shutdown()

    # -- state --------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        """Whether the board's thread still runs."""
        return self._thread.is_alive()

    @property
    def messages(self) -> list[str]:
        """What the board said about its link (lost, reopened), in order."""
        return list(self._messages)

    def summary(self) -> dict[str, Any]:
        """The board's figures (:class:`firmware_sim.config.BoardSummary`, its event counts
        named as the STATUS record's: ``events_generated``, ``events_sent``,
        ``events_dropped``, ``events_queued``; times in s, ``lateness_ms`` in ms): final
        once the run ended, else as of now."""
        summary = self._summary if self._summary is not None else self.emulator.summary()
        return {SUMMARY_NAMES.get(k, k): v for k, v in summary.as_dict().items()}

    def score(self) -> dict[str, Any]:
        """The board's score of the decoder under test: its DECISIONs, its ANSWERs per task
        (``"tasks"``) and, with a held object, ``"grasp"``; what ``serve --score`` writes.
        Final once the run ended (:meth:`wait`, :meth:`close`)."""
        return board_score(self.emulator)

    # -- the end ------------------------------------------------------------------------
    def wait(self, timeout: float | None = None) -> bool:
        """Wait up to ``timeout`` s (None: no limit) for the run to end by itself; whether
        it ended. An exception of the board's thread is raised here."""
        self._thread.join(timeout)
        self._raise()
        return not self._thread.is_alive()

    def __repr__(self) -> str:
        size = self.emulator.config.size
        return (f"skinhil.Board({size[0]}x{size[1]}, {self.transport.name}, "
                f"{'running' if self.running else 'ended'})")
