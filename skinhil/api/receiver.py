"""``skinhil.Receiver``: the reference receiver (:class:`skinhil.receiver.Receiver`) on a
background thread, for a notebook or a script: the board's events in batches, its records,
the link counters, and the host's commands (DECISION, ANSWER, GRIP) sent back to it.

It needs no board emulator (the receiver side never imports ``firmware_sim``): it reads any
link a real board or ``skinhil serve`` sends on.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

import protocols
from skinhil.api.background import BackgroundRun
from skinhil.api.links import open_api_link
from skinhil.events import EVENT_DTYPE
from skinhil.model.geometry import MeshSize, spring_count
from skinhil.model.psp import PSPParams
from skinhil.receiver import OnsetParams, ReceiverListener, ReceiverParams, ScoredDecision
from skinhil.receiver import Receiver as ReferenceReceiver
from skinhil.receiver.answer import CommandSender
from skinhil.receiver.model_file import load_window_decoder
from skinhil.tasks.registry import by_name
from skinhil.transports import Transport

POLL_S = 0.02
"""How long (s) the receiver's thread waits on the link per read."""
STOP_TIMEOUT_S = 5.0
"""Longest :meth:`Receiver.close` waits for the receiver's thread (s)."""
NEVER_SPIKES = 1e12
"""An onset rule's least excess (spikes) no window reaches: without a decoder the receiver
detects no onset and decides nothing."""


class EventsOnly:
    """The decoder of a receiver given no model: it is never asked (no onset is detected,
    :data:`NEVER_SPIKES`); it tells the receiver the stream's channel count and step."""

    def __init__(self, n_channels: int, dt_s: float = 1e-4) -> None:
        self.dt_s = dt_s
        self.n_channels = n_channels
        self.psp_params = PSPParams()
        self.window_steps = 1
        self.classes = np.zeros(0, dtype=np.int64)

    def decide(self, window_psp: np.ndarray) -> tuple[int, np.ndarray]:
        raise RuntimeError("a receiver without a model decides nothing")


class _Collector(ReceiverListener):
    """The events, decisions and ACKs the receiver's thread hands over."""

    def __init__(self) -> None:
        self.batches: queue.Queue[np.ndarray] = queue.Queue()
        self.decisions: list[ScoredDecision] = []
        self.acks: dict[int, Any] = {}

    def on_events(self, events: np.ndarray, host_time_s: float) -> None:
        self.batches.put(np.array(events, dtype=EVENT_DTYPE))

    def on_decision(self, decision: ScoredDecision) -> None:
        self.decisions.append(decision)

    def on_ack(self, ack: Any) -> None:
        self.acks[int(ack.token)] = ack


class Receiver(BackgroundRun):
    """Receive one board's stream on ``link`` on a background thread.

    ``link``: a serial device path (``board.peer``), a link URL (``serial:...``,
    ``can:vcan0``, ``udp::9000``; docs/links.md) or an open
    :class:`~skinhil.transports.Transport`; ``board_id`` the board on a CAN bus. ``model``: a
    decoder file (``skinhil train``) the reference receiver decides with (its decisions in
    :attr:`decisions`); None decides nothing. ``size`` (rows, columns of the top layer) sets
    the channel count when no model says it.
    """

    stop_timeout_s = STOP_TIMEOUT_S

    def __init__(self, link: str | Transport[Any], *, model: str | Path | None = None,
                 size: MeshSize = (6, 6), board_id: int = 0,
                 params: ReceiverParams | None = None) -> None:
        n_channels = spring_count(size)
        decoder: Any = (EventsOnly(n_channels) if model is None
                        else load_window_decoder(model, n_channels=n_channels))
        if model is None:
            base = params or ReceiverParams()
            params = ReceiverParams(
                onset=OnsetParams(min_excess_spikes=NEVER_SPIKES), guard_s=base.guard_s,
                max_guard_s=base.max_guard_s, match_window_s=base.match_window_s,
                silence_s=base.silence_s)
        self.transport: Transport[Any] = open_api_link(link, "host")
        self.reference = ReferenceReceiver(self.transport, decoder, params, board_id)
        """The reference receiver underneath (its counters, clock and scoreboard)."""
        self._collected = _Collector()
        self.reference.add_listener(self._collected)
        self._sender = CommandSender(self.transport, board_id)
        self._token = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="skinhil-receiver", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self.reference.run(stop=self._stop)
            self.reference.drain()
            self.reference.flush()
        except BaseException as exc:  # raised again in the caller's thread
            self._error = exc

    # -- events ---------------------------------------------------------------------------
    @property
    def receiving(self) -> bool:
        """Whether the thread still reads (until :meth:`close`, the board's RUN_END or a
        link that went away)."""
        return self._thread.is_alive()

    def batches(self, timeout_s: float | None = None) -> Iterator[np.ndarray]:
        """The event batches (``skinhil.EVENT_DTYPE``: ``t`` µs of board time, ``addr`` the
        channel) as they arrive, until the receiver stops or ``timeout_s`` (s) passes."""
        end = None if timeout_s is None else time.monotonic() + timeout_s
        while True:
            left = None if end is None else end - time.monotonic()
            if left is not None and left <= 0:
                return
            try:
                yield self._collected.batches.get(timeout=min(POLL_S * 5, left or POLL_S * 5))
            except queue.Empty:
                if not self.receiving and self._collected.batches.empty():
                    self._raise()
                    return

    def __iter__(self) -> Iterator[np.ndarray]:
        return self.batches()

    def read(self, seconds: float) -> np.ndarray:
        """Every event received in the next ``seconds`` (s of wall time; less when the
        board's run ends first) with those already waiting, as one structured array."""
        parts = list(self.batches(seconds))
        return np.concatenate(parts) if parts else np.zeros(0, dtype=EVENT_DTYPE)

    @property
    def decisions(self) -> list[ScoredDecision]:
        """The reference decoder's decisions so far (none without a model)."""
        return list(self._collected.decisions)

    # -- the board's records and the link ---------------------------------------------------
    @property
    def status(self) -> Any:
        """The board's last STATUS record (``protocols.Status``), None before any."""
        return self.reference.last_status

    @property
    def session(self) -> Any:
        """The board's last SESSION record (``protocols.Session``), None before any."""
        return self.reference.session

    @property
    def run_end(self) -> Any:
        """The board's RUN_END record once its run ended, else None."""
        return self.reference.run_end

    def link_report(self) -> dict[str, int]:
        """The link counters (:class:`skinhil.receiver.LinkReport`): events decoded, CRC
        errors, frames lost, the board's own counts, ``lost_on_link`` and
        ``sent_before_join`` (what the board had sent before this receiver joined)."""
        return self.reference.link_report().as_dict()

    # -- commands to the board ----------------------------------------------------------
    def _send(self, record: Any, what: str) -> int:
        if not self._sender.send(record, what):
            return -1
        return int(record.token)

    def _next_token(self) -> int:
        with self._lock:
            self._token = (self._token + 1) % 65536
            return self._token

    def decide(self, stimulus_id: int, confidence: float | None = None) -> int:
        """Send a DECISION (the stimulus decided on, a confidence 0..1 or None); its token,
        or -1 when the link had no room (SPEC.md §3.5.1)."""
        return self._send(protocols.Decision(self._next_token(), int(stimulus_id), confidence),
                          f"DECISION for stimulus {stimulus_id}")

    def answer(self, task: str | int, *values: float) -> int:
        """Send an ANSWER to ``task`` (a task name, ``"localisation"``, or its wire id) with
        its values in the task's units (mm, N, Hz, ...); its token, or -1 (SPEC.md §3.5.3)."""
        task_id = by_name(task).layout.task if isinstance(task, str) else int(task)
        return self._send(protocols.Answer(self._next_token(), task_id,
                                           tuple(float(v) for v in values)),
                          f"ANSWER to task {task}")

    def grip(self, grip_n: float) -> int:
        """Send a GRIP of ``grip_n`` (N) to the held object; its token, or -1."""
        return self._send(protocols.Command(self._next_token(), protocols.CommandCode.GRIP,
                                            float(grip_n)), f"GRIP of {grip_n:g} N")

    def ack(self, token: int) -> Any:
        """The board's ACK of the command sent with ``token`` (``protocols.Ack``: ``ok``,
        ``reason``), None while none came."""
        return self._collected.acks.get(token)

    def commands(self) -> dict[str, int]:
        """The commands this receiver sent: ``sent``, ``unsent`` (the link had no room),
        ``acked``, ``nacked`` (the board's answers received) and ``unanswered``."""
        tokens = set(range(1, self._token + 1))
        answered = [a for t, a in self._collected.acks.items() if t in tokens]
        acked = sum(1 for a in answered if a.ok)
        sent = self._sender.sent
        return {"sent": sent, "unsent": self._sender.unsent, "acked": acked,
                "nacked": len(answered) - acked, "unanswered": sent - len(answered)}

    # -- the end ----------------------------------------------------------------------------
    def __repr__(self) -> str:
        return (f"skinhil.Receiver({self.transport.name}, "
                f"{'receiving' if self.receiving else 'stopped'})")
