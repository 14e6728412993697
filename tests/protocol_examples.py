"""The worked examples of protocols/SPEC.md, built with the encoders (shared by the tests).

Each example is a name and a function returning the wire form as text: serial examples as
hex bytes (one packet per line), CAN examples in the syntax of can-utils' ``candump`` and
``cansend``: ``ID#DATA`` for classic frames, ``ID##<flags>DATA`` for CAN FD frames (flags
0: no bit-rate switch), ID and data in hex.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from protocols import (
    Ack,
    Answer,
    CanEncoder,
    CanFrame,
    Command,
    CommandCode,
    Decision,
    Marker,
    MarkerPhase,
    NackReason,
    RunEnd,
    RunEndReason,
    SerialEncoder,
    Session,
    SessionReason,
    Status,
    StimulusEntry,
    SuiteEntry,
    Task,
    TaskEntry,
    table_digest,
)
from skinhil.events import make_events

STATUS = Status(t_us=1_000_000, events_generated=20_000, events_sent=19_990, events_dropped=5,
                events_queued=5, late_ticks=1, rx_errors=0, running=True,
                dropped_fifo_full=3, dropped_stopped=2, dropped_link_down=0,
                dropped_shutdown=0, markers_sent=8, markers_dropped=1)
MARKER = Marker(t_us=250_000, stimulus_id=3, phase=MarkerPhase.ONSET)
COMMAND = Command(token=0x1234, opcode=CommandCode.SET_SNR, arg=10.0)
DECISION = Decision(token=0x1235, stimulus_id=3, confidence=0.5)
"""The decoder under test decided on stimulus 3, confidence 0.5 (127 / 254)."""
ANSWERS = (Answer(0x1236, Task.LOCALISATION, (1.25, -2.5)), Answer(0x1237, Task.FORCE, (0.3,)),
           Answer(0x1238, Task.SLIP, ()), Answer(0x1239, Task.VIBRATION, (100.0,)))
"""A decoder under test's ANSWERs (SPEC.md §3.5.3): a touch at (1.25, -2.5) mm, of 0.3 N, a
slip, a vibration of 100 Hz."""
ACK = Ack(token=0x1234, opcode=CommandCode.SET_STIMULUS, ok=False,
          reason=NackReason.UNKNOWN_STIMULUS)
GRIP = Command(token=0x1240, opcode=CommandCode.GRIP, arg=0.75)
"""A grip of 0.75 N (binary32 0x3F400000)."""
GRIP_NACK = Ack(token=0x1241, opcode=CommandCode.GRIP, ok=False, reason=NackReason.GRIP_LIMIT)
"""A GRIP refused: above the largest grip or faster than the largest rate."""
EVENTS = make_events([0, 0, 300, 900], [5, 17, 337, 2])
"""Four events: channels 5 and 17 at 0 µs, 337 at 300 µs, 2 at 900 µs."""
BURST = make_events([200] * 25, list(range(0, 250, 10)))
"""25 channels (0, 10, ..., 240) in the step at 200 µs: sent as a bitmap."""
ONE = make_events([0], [7])
"""One event: channel 7 at 0 µs (a CAN frame with empty slots)."""
WIDE_CHANNELS = 15_730
"""A 32x32 skin's channel count: its stream uses the wide format (version 4)."""
WIDE_EVENTS = make_events([0, 0, 300, 900], [5, 15_000, 337, 12_810])
"""Four events of a wide stream: channels 5 and 15000 at 0 µs, 337 at 300 µs, 12810 at 900 µs."""


TABLE = [StimulusEntry(0, "0deg_0.1N"), StimulusEntry(10, "A")]
"""A stimulus table of two rows (a direction condition and the paper's stimulus A)."""
SESSION = Session(t_us=0, reason=SessionReason.START, version=3, board_id=1, running=True,
                  n_channels=338, rows=6, cols=6, step_us=100, tick_us=1000, snr_db=10.0,
                  response_window_us=500_000, n_stimuli=len(TABLE),
                  table_digest=table_digest(TABLE), tasks=0x000F, blind=True)
"""The session of a run's start: board 1, the 6x6 skin, 100 µs steps, 1 ms ticks, 10 dB,
0.5 s response window, the two-row table :data:`TABLE`; it scores classification,
localisation, force and slip (tasks 0x000F) on a blind link."""
RUN_END = RunEnd(t_us=60_000_000, reason=RunEndReason.DURATION)
"""The run ended after its 60 s."""
SESSION_RECORDS = (SESSION, *TABLE)
"""A SESSION and the STIMULUS records that follow it."""
SUITE_RECORDS = (SuiteEntry("tactile", 1, "force", 1), TaskEntry(Task.FORCE, 0.05, "N"))
"""The SUITE of the case ``tactile-v1:force`` and its one TASK: FORCE within 0.05 N."""
TASK_CLASSES = TaskEntry(Task.VIBRATION, None, "Hz", (50.0, 100.0, 200.0, 300.0))
"""The TASK of the case ``tactile-v1:vibration``: no tolerance, 4 classes in Hz."""


def distinct_events(t_us: object, addr: object) -> np.ndarray:
    """Events at times ``t_us`` (µs) on channels ``addr``, sorted by time and channel, each
    (time, channel) pair once: a channel spikes at most once per step (SPEC.md §3.1), so
    random test streams drop their repeats before an encoder sees them."""
    pairs = np.unique(np.array([np.asarray(t_us), np.asarray(addr)], dtype=np.int64), axis=1)
    return make_events(pairs[0], pairs[1])


def framed(body: bytes) -> bytes:
    """``body`` as one serial packet (COBS, CRC, delimiter) with a good CRC: hand-made
    bodies, for the decoder's layout checks."""
    from protocols.framing import frame_into

    buf = np.zeros(len(body) + 2, dtype=np.uint8)
    buf[:len(body)] = np.frombuffer(body, dtype=np.uint8)
    out = np.zeros(2 * len(body) + 16, dtype=np.uint8)
    return out[:frame_into(buf, len(body), out, 0)].tobytes()


def _split_packets(data: bytes) -> str:
    lines, start = [], 0
    for i, b in enumerate(data):
        if b == 0:
            lines.append(data[start:i + 1].hex(" "))
            start = i + 1
    return "\n".join(lines)


def _frames(frames: list[CanFrame]) -> str:
    return "\n".join(f"{f.arbitration_id:03X}#{'#0' if f.is_fd else ''}{f.data.hex().upper()}"
                     for f in frames)


def _serial(fn: Callable[[SerialEncoder], bytes]) -> Callable[[], str]:
    return lambda: _split_packets(fn(SerialEncoder()))


def _can(fd: bool, fn: Callable[[CanEncoder], list[CanFrame]]) -> Callable[[], str]:
    return lambda: _frames(fn(CanEncoder(board_id=1, fd=fd)))


EXAMPLES: dict[str, Callable[[], str]] = {
    "serial-events": _serial(lambda e: e.events(EVENTS, 1000)),
    "serial-wide-events": lambda: _split_packets(
        SerialEncoder(n_channels=WIDE_CHANNELS).events(WIDE_EVENTS, 1000)),
    "serial-bitmap": _serial(lambda e: e.events(BURST, 1000)),
    "serial-status": _serial(lambda e: e.status(STATUS)),
    "serial-marker": _serial(lambda e: e.marker(MARKER)),
    "serial-command": _serial(lambda e: e.command(COMMAND)),
    "serial-ack": _serial(lambda e: e.ack(ACK)),
    "serial-decision": _serial(lambda e: e.command(DECISION)),
    "serial-answers": _serial(lambda e: b"".join(e.command(a) for a in ANSWERS)),
    "serial-grip": _serial(lambda e: e.command(GRIP) + e.ack(GRIP_NACK)),
    "serial-session": _serial(lambda e: b"".join(e.session_record(r) for r in SESSION_RECORDS)),
    "serial-run-end": _serial(lambda e: e.session_record(RUN_END)),
    "serial-suite": _serial(lambda e: b"".join(e.session_record(r) for r in SUITE_RECORDS)),
    "serial-task-classes": _serial(lambda e: e.session_record(TASK_CLASSES)),
}
for _fd, _tag in ((False, "can"), (True, "canfd")):
    EXAMPLES[f"{_tag}-events"] = _can(_fd, lambda e: e.events(EVENTS, 1000))
    EXAMPLES[f"{_tag}-one-event"] = _can(_fd, lambda e: e.events(ONE, 100))
    EXAMPLES[f"{_tag}-status"] = _can(_fd, lambda e: e.status(STATUS))
    EXAMPLES[f"{_tag}-marker"] = _can(_fd, lambda e: e.marker(MARKER))
    EXAMPLES[f"{_tag}-command"] = _can(_fd, lambda e: e.command(COMMAND))
    EXAMPLES[f"{_tag}-ack"] = _can(_fd, lambda e: e.ack(ACK))
    EXAMPLES[f"{_tag}-decision"] = _can(_fd, lambda e: e.command(DECISION))
    EXAMPLES[f"{_tag}-answers"] = _can(_fd, lambda e: [f for a in ANSWERS for f in e.command(a)])
    EXAMPLES[f"{_tag}-grip"] = _can(_fd, lambda e: e.command(GRIP) + e.ack(GRIP_NACK))
    EXAMPLES[f"{_tag}-session"] = _can(_fd, lambda e: [
        f for r in SESSION_RECORDS for f in e.session_record(r)])
    EXAMPLES[f"{_tag}-run-end"] = _can(_fd, lambda e: e.session_record(RUN_END))
    EXAMPLES[f"{_tag}-suite"] = _can(_fd, lambda e: [
        f for r in SUITE_RECORDS for f in e.session_record(r)])
    EXAMPLES[f"{_tag}-task-classes"] = _can(_fd, lambda e: e.session_record(TASK_CLASSES))
    EXAMPLES[f"{_tag}-wide-events"] = (lambda fd: lambda: _frames(
        CanEncoder(board_id=1, fd=fd, n_channels=WIDE_CHANNELS).events(WIDE_EVENTS, 1000)))(_fd)
