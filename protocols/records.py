"""The non-event records the wire protocols carry, and the link counters a decoder keeps.

Times are board time in microseconds (``t_us``, int); counters are cumulative since the
board started. Every record is a frozen dataclass so it can be compared and hashed.
"""

from __future__ import annotations

import dataclasses
import enum

import numpy as np

from protocols.answer_layouts import BUILT_IN_LAYOUTS
from protocols.events import EVENT_DTYPE


class CommandCode(enum.IntEnum):
    """Host→board command opcodes (one byte on the wire)."""

    START = 1
    """Start publishing events (``arg`` ignored)."""
    STOP = 2
    """Stop publishing events; the board keeps its time and counters (``arg`` ignored)."""
    SET_STIMULUS = 3
    """Apply stimulus number ``arg`` (int) now."""
    SET_SCHEDULE = 4
    """Run schedule number ``arg`` (int) from now."""
    SET_SNR = 5
    """Set the neuron noise to ``arg`` dB (float; ``inf`` means no noise)."""
    QUERY_STATUS = 6
    """Ask for a status packet now (sent right after the ACK)."""
    PING = 7
    """Do nothing but acknowledge (link check)."""
    DECISION = 8
    """The decoder under test's answer: a :class:`Decision` (stimulus id, confidence)."""
    QUERY_SESSION = 9
    """Ask for the session record and the stimulus table now (sent right after the ACK)."""
    ANSWER = 10
    """The decoder under test's answer to a task: an :class:`Answer` (task id, values)."""
    GRIP = 12
    """Set the hand's grip: ``arg`` the normal force set-point in N (float, binary32 on the
    wire), from the board's next tick on (SPEC.md §3.5.6)."""


class NackReason(enum.IntEnum):
    """Why a command was refused (``NONE`` in a positive ACK). One byte on the wire."""

    NONE = 0
    UNKNOWN_COMMAND = 1
    BAD_ARGUMENT = 2
    UNKNOWN_STIMULUS = 3
    UNKNOWN_SCHEDULE = 4
    BUSY = 5
    NOT_RUNNING = 6
    INTERNAL_ERROR = 7
    REPLAYING = 8
    """The link is playing a recording (``serve --replay``): no command is executed."""
    UNKNOWN_TASK = 9
    """An ANSWER names a task id this document does not define (5..15)."""
    TASK_NOT_POSED = 10
    """An ANSWER names a task the board does not score in this run (no truth for it)."""
    GRIP_LIMIT = 11
    """A GRIP above the largest grip, or changing it faster than the largest rate."""
    NO_OBJECT = 12
    """A GRIP to a board that holds no object (it runs no grasp task)."""


class MarkerPhase(enum.IntEnum):
    """Which moment of a stimulus a ground-truth marker stamps."""

    ONSET = 0
    """The stimulus starts pressing."""
    END = 1
    """The indentation phase ends (the force starts decaying)."""


class SessionReason(enum.IntEnum):
    """Why the board sent a :class:`Session` record (one byte on the wire)."""

    START = 0
    """The run starts (the first record of a run)."""
    RECONNECT = 1
    """The link came back after it was lost (the receiver may have restarted)."""
    REQUEST = 2
    """A host asked for it (``QUERY_SESSION``)."""


class RunEndReason(enum.IntEnum):
    """Why a run ended (one byte of the :class:`RunEnd` record)."""

    DURATION = 0
    """The run's set duration of board time elapsed."""
    STOP = 1
    """The program running the board was asked to stop."""
    SIGNAL = 2
    """The operator stopped it with a signal (SIGINT: Ctrl-C, or SIGTERM)."""
    ERROR = 3
    """An internal error ended it."""


@dataclasses.dataclass(frozen=True)
class Session:
    """What a receiver needs to know about the board and the run (SPEC.md §3.7).

    ``t_us`` board time when sent (µs); ``step_us`` the event time step (µs); ``tick_us``
    the publish tick (µs); ``snr_db`` the neuron noise level (dB, ``inf``: none);
    ``response_window_us`` how long after an onset a DECISION is scored (µs);
    ``n_stimuli`` and ``table_digest`` describe the stimulus table whose
    :class:`StimulusEntry` records follow this one (CRC-32 of their payloads); ``tasks``
    the tasks whose ANSWERs the board scores, bit ``n`` for :class:`Task` ``n`` (0: not
    announced, a board of an earlier revision); ``blind``: no MARKER on this link (§3.5.5).
    """

    t_us: int
    reason: SessionReason | int
    version: int
    board_id: int
    running: bool
    n_channels: int
    rows: int
    cols: int
    step_us: int
    tick_us: int
    snr_db: float
    response_window_us: int
    n_stimuli: int
    table_digest: int
    tasks: int = 0
    blind: bool = False
    held_object: bool = False
    """The board holds an object that GRIP commands act on (flags bit 2, §3.5.6)."""


@dataclasses.dataclass(frozen=True)
class StimulusEntry:
    """One row of the stimulus table: the MARKERs' ``stimulus_id`` and its name (UTF-8,
    1..64 bytes on the wire)."""

    stimulus_id: int
    name: str


@dataclasses.dataclass(frozen=True)
class SuiteEntry:
    """The suite case the board plays (SPEC.md §3.7): the suite's ``name`` and ``version``
    and the ``case`` (all empty / 0: the board plays no suite), and ``n_tasks``, the
    :class:`TaskEntry` records that follow it (UTF-8 names of 0..32 bytes)."""

    name: str = ""
    version: int = 0
    case: str = ""
    n_tasks: int = 0


@dataclasses.dataclass(frozen=True)
class TaskEntry:
    """A task the board poses and its terms (SPEC.md §3.7): the ``task`` (its ANSWER id),
    the ``tolerance`` of a right answer in ``unit`` (None: the task has none, a class or an
    event is right or wrong as a whole), the ``unit`` (an SI symbol, 0..8 UTF-8 bytes) and
    the ``classes`` a class task's answers choose from, in ``unit`` (binary32 on the wire,
    at most 24)."""

    task: Task | int
    tolerance: float | None = None
    unit: str = ""
    classes: tuple[float, ...] = ()


@dataclasses.dataclass(frozen=True)
class RunEnd:
    """The last record of a run: it ended at board time ``t_us`` (µs) for ``reason``."""

    t_us: int
    reason: RunEndReason | int


@dataclasses.dataclass(frozen=True)
class Status:
    """Board status / heartbeat: cumulative counters at board time ``t_us`` (µs).

    Invariants kept by the board in every status, the last one included:
    ``events_generated == events_sent + events_dropped + events_queued`` and
    ``events_dropped == dropped_fifo_full + dropped_stopped + dropped_link_down +
    dropped_shutdown``. Ground-truth markers are counted apart: ``markers_sent`` were put on
    the wire, ``markers_dropped`` never will be (the board was stopped or the link was gone
    when they fell due). On the wire each counter is sent modulo 2**32 (some 2**24 on
    classic CAN) and a decoder unwraps it (see SPEC.md).
    """

    t_us: int
    events_generated: int
    events_sent: int
    events_dropped: int
    events_queued: int
    late_ticks: int
    rx_errors: int
    running: bool
    dropped_fifo_full: int = 0
    """Events dropped because the transmit FIFO was full (link too slow)."""
    dropped_stopped: int = 0
    """Events generated while publishing was stopped."""
    dropped_link_down: int = 0
    """Events generated while the transport was gone."""
    dropped_shutdown: int = 0
    """Events still queued when the board shut down and its final drain timed out."""
    markers_sent: int = 0
    """Ground-truth markers put on the wire."""
    markers_dropped: int = 0
    """Ground-truth markers not sent: due while the board was stopped or the link was gone."""


@dataclasses.dataclass(frozen=True)
class Marker:
    """Ground truth: stimulus ``stimulus_id`` reached ``phase`` at board time ``t_us`` (µs)."""

    t_us: int
    stimulus_id: int
    phase: MarkerPhase


@dataclasses.dataclass(frozen=True)
class Command:
    """A host→board command; ``token`` (0..65535) is echoed in the ACK.

    ``arg`` is an int (stimulus/schedule number, 0..2**32-1) or, for ``SET_SNR``, a float in
    dB (sent as IEEE-754 binary32; ``inf`` allowed), for ``GRIP`` a float in N (binary32).
    """

    token: int
    opcode: CommandCode | int
    """A :class:`CommandCode`; an unknown code decodes as a plain int (to be NACKed)."""
    arg: int | float = 0


@dataclasses.dataclass(frozen=True)
class Ack:
    """The board's answer to the command with ``token``: ``ok`` or refused for ``reason``."""

    token: int
    opcode: CommandCode | int
    ok: bool
    reason: NackReason | int = NackReason.NONE
    """A :class:`NackReason`; an unknown code decodes as a plain int."""


DECISION_MAX_STIMULUS_ID = (1 << 24) - 1
"""The largest stimulus id a DECISION carries (24 bits, SPEC.md §3.5)."""
CONFIDENCE_STEPS = 254
"""A DECISION's confidence travels as ``round(confidence * 254)`` in 0..254 (255: none)."""


@dataclasses.dataclass(frozen=True)
class Decision:
    """The decoder under test's answer (host→board COMMAND of opcode ``DECISION``).

    ``stimulus_id`` (0..2**24-1) is the stimulus the decoder decided on, in the id space of
    the ground-truth :class:`Marker` records; ``confidence`` (0..1, or None when the decoder
    gives none) travels in steps of 1/254. ``token`` (0..65535) is echoed in the ACK.
    """

    token: int
    stimulus_id: int
    confidence: float | None = None

    @property
    def opcode(self) -> CommandCode:
        """Always :attr:`CommandCode.DECISION` (so a Decision is answered like a command)."""
        return CommandCode.DECISION


class Task(enum.IntEnum):
    """What an :class:`Answer` answers (4 bits on the wire, SPEC.md §3.5.3)."""

    CLASSIFICATION = 0
    """Which stimulus: values ``(stimulus_id,)`` (a DECISION without confidence)."""
    LOCALISATION = 1
    """Where the touch is: values ``(x_mm, y_mm)``, skin coordinates (mm)."""
    FORCE = 2
    """How hard: values ``(force_n,)``, the normal force (N)."""
    SLIP = 3
    """The object slips now: no values (the answer's arrival is what is scored)."""
    VIBRATION = 4
    """What vibrates: values ``(frequency_hz,)`` (Hz)."""


ANSWER_UNITS: dict[int, tuple[str, ...]] = {lay.task: lay.fields for lay in BUILT_IN_LAYOUTS}
"""The names (with units) of each built-in task's values, in order (a task added at run time:
:data:`protocols.answer_layouts.ANSWER_LAYOUTS`)."""
ANSWER_SCALE: dict[int, float] = {lay.task: lay.scale for lay in BUILT_IN_LAYOUTS
                                  if lay.fields}
"""One wire step of each built-in task's values: 1 id, 0.01 mm, 1 µN, 1 mHz (SPEC.md
§3.5.3)."""


@dataclasses.dataclass(frozen=True)
class Answer:
    """The decoder under test's answer to a task (host→board COMMAND of opcode ``ANSWER``).

    ``task`` a :class:`Task` (an unknown id decodes as a plain int, to be NACKed);
    ``values`` the task's values in the units of :data:`ANSWER_UNITS` (an id; mm; N; none;
    Hz), sent in the steps of :data:`ANSWER_SCALE`; an unknown task carries its raw 28-bit
    field as its one value. ``token`` (0..65535) is echoed in the ACK.
    """

    token: int
    task: Task | int
    values: tuple[float, ...] = ()

    @property
    def opcode(self) -> CommandCode:
        """Always :attr:`CommandCode.ANSWER` (so an Answer is answered like a command)."""
        return CommandCode.ANSWER


SessionRecord = Session | StimulusEntry | SuiteEntry | TaskEntry | RunEnd
"""A session record (serial type 7, CAN classes 8..12: SPEC.md §3.7)."""

Record = (Status | Marker | Command | Decision | Answer | Ack | Session | StimulusEntry
          | SuiteEntry | TaskEntry | RunEnd)
"""Any non-event record a decoder returns."""

COMMAND_KEY_DTYPE = np.dtype([("token", "<u2"), ("opcode", "u1")])
"""Token and opcode of a COMMAND unit not built into a record (:class:`DecodeResult`)."""


@dataclasses.dataclass
class LinkCounters:
    """What a decoder saw on the link, cumulative since it was created (see SPEC.md §7).

    Exact (by the protocol): ``frames_ok``, ``crc_errors``, ``malformed``,
    ``bytes_discarded``, ``events_decoded``, ``events_untimed``, and ``events_lost`` as of the
    last received status. ``frames_lost`` is exact while fewer than one sequence period
    (serial 256, CAN 16 / 256 frames) is lost in a row; ``duplicates`` counts back-to-back
    repeats only. Host COMMAND frames seen on a CAN bus have their own sequence counter and
    their own gap counts (``command_seq_gaps``, ``commands_lost``), apart from the board's.
    """

    frames_ok: int = 0
    """Frames (packets) that passed every check and were decoded."""
    crc_errors: int = 0
    """Serial: delimited candidate frames whose CRC failed (or too short to hold one)."""
    malformed: int = 0
    """Frames with a good CRC (serial) or a known ID (CAN) but an invalid layout."""
    resyncs: int = 0
    """Times the decoder had to skip data to find the next frame start."""
    bytes_discarded: int = 0
    """Serial bytes that belonged to no good frame (corrupted frames, noise, overflow)."""
    seq_gaps: int = 0
    """Times the sequence number jumped (one gap may hide many frames)."""
    frames_lost: int = 0
    """Frames missing according to the sequence numbers."""
    duplicates: int = 0
    """Frames that repeated the previous sequence number (ignored)."""
    foreign_frames: int = 0
    """CAN frames with an ID that is not this board's (ignored)."""
    events_decoded: int = 0
    """Events returned to the caller."""
    events_untimed: int = 0
    """Events received in frames whose time base (SYNC) was lost: not returned."""
    events_lost: int = 0
    """Events the board put on the wire that never came out of this decoder, exact as of
    the last status received (board count minus decoded count since the first status)."""
    events_lost_reported: int = 0
    """The board's own ``events_dropped`` from the last status received."""
    events_before_join: int = 0
    """Events the board put on the wire before the first status received that did not come
    out of this decoder: what a receiver that joined a run late missed (not in
    ``events_lost``, which counts from that status on)."""
    syncs: int = 0
    """SYNC (time base) frames received."""
    command_seq_gaps: int = 0
    """CAN: times a host's COMMAND sequence number jumped (not the board's frames)."""
    commands_lost: int = 0
    """CAN: COMMAND frames missing according to the host's sequence numbers."""
    acks_lost: int = 0
    """CAN: ACK frames missing according to the ACK counter (byte 1 bits 7..1, modulo 128,
    SPEC.md §5.6): exact while fewer than 128 ACKs are lost in a row, even when whole
    periods of the classic 4-bit frame sequence were lost (a receive-queue overflow)."""
    late_frames: int = 0
    """Serial: packets arriving 1..8 sequence numbers behind the last (reordered UDP
    datagrams): dropped (their events in ``events_untimed``), the time base kept."""


@dataclasses.dataclass(frozen=True)
class DecodeResult:
    """What one ``feed`` call produced: events (``EVENT_DTYPE``, time order) and records.

    A ``feed`` given ``max_records`` builds at most that many records; the COMMAND units past
    them come back in ``excess_commands`` only as their token and opcode
    (:data:`COMMAND_KEY_DTYPE`, stream order), and other records past them are counted in
    ``records_skipped``: a receiver flooded with units pays a compiled pass for them, not a
    Python object each.
    """

    events: np.ndarray
    records: list[Record]
    excess_commands: np.ndarray = dataclasses.field(
        default_factory=lambda: np.empty(0, dtype=COMMAND_KEY_DTYPE))
    records_skipped: int = 0

    @staticmethod
    def empty() -> DecodeResult:
        """A result with no events and no records."""
        return DecodeResult(np.empty(0, dtype=EVENT_DTYPE), [])


@dataclasses.dataclass(frozen=True)
class CanFrame:
    """One CAN or CAN FD frame: 11-bit ``arbitration_id`` and ``data`` (0..8 or 0..64 bytes)."""

    arbitration_id: int
    data: bytes
    is_fd: bool = False
