"""The CAN databases (DBC) of the CAN layouts (SPEC.md §5), generated for any board id.

One generator, :func:`dbc_text`, writes the DBC of board ``board_id`` (0..15) for classic
CAN or CAN FD; ``protocols/skinhil.dbc`` and ``protocols/skinhil_fd.dbc`` are its output for
board 0 (``skinhil dbc --board-id N [--fd] --out FILE`` writes the others). Every frame type
has one fixed length on the wire, so cantools, SavvyCAN and candump users decode every frame
with default settings. Event slots after a frame's last event hold the all-ones address
(511; wide: 1048575), which the DBC names ``NONE`` (an FD frame also says how many events it
holds in ``Count``). A COMMAND frame is multiplexed by its ``Opcode``: ``Arg`` for opcodes
1..7, ``DecisionStimulusId`` and ``DecisionConfidence`` for DECISION (SPEC.md §3.5.1),
``AnswerTask`` and the task's values for ANSWER (§3.5.3; the task multiplexes them),
``GripN`` (binary32, N) for GRIP (§3.5.6).
"""

from __future__ import annotations

from dataclasses import dataclass

from protocols import can_kernels as k
from protocols.answer_layouts import ANSWER_LAYOUTS
from protocols.can_codec import STATUS_LEN_FD, can_id
from protocols.constants import PROTOCOL_VERSION
from protocols.errors import ProtocolError
from protocols.records import (
    CONFIDENCE_STEPS,
    CommandCode,
    MarkerPhase,
    NackReason,
    RunEndReason,
    SessionReason,
    Task,
)
from protocols.session_layout import (
    CLASSIC_CHUNK,
    FD_CHUNK,
    FD_FRAME_BYTES,
    MAX_CLASSES,
    MAX_NAME_BYTES,
    MAX_SUITE_NAME_BYTES,
    MAX_UNIT_BYTES,
    RUN_END_FIELDS,
    SESSION_FIELDS,
    STIMULUS_HEAD,
    SUITE_FIELDS,
    SUITE_HEAD,
    TASK_FIELDS,
    TASK_HEAD,
)
from protocols.status_layout import CLASSIC_STATUS_MUX, STATUS_WORDS

BOARD, HOST = "BOARD", "HOST"
_FD_FORMAT = 14
"""``VFrameFormat`` value of a standard-ID CAN FD frame."""


@dataclass(frozen=True)
class Signal:
    """A little-endian unsigned field: ``bits`` bits from bit ``start`` of the data."""

    name: str
    start: int
    bits: int
    unit: str = ""
    mux: str = ""
    """``"M"`` for the multiplexer, ``"m<n>"`` for a field of mux value n, else ``""``."""
    mux_range: tuple[int, int] | None = None
    """Mux values ``(first, last)`` of a field present for several (DBC extended
    multiplexing, ``SG_MUL_VAL_``); its ``mux`` names the first."""
    choices: tuple[tuple[int, str], ...] = ()
    float32: bool = False
    """An IEEE-754 binary32 (``SIG_VALTYPE_`` 1), not an unsigned integer."""
    scale: float = 1.0
    """Physical value = raw × scale."""
    signed: bool = False
    """Two's complement (``@1-``), not unsigned."""
    multiplexer: str = ""
    """For a field of a nested multiplexer (``mux`` "m<n>" of a signal other than the
    message's "M" one): that multiplexer's name (``SG_MUL_VAL_``)."""


@dataclass(frozen=True)
class Message:
    """One frame type: class (the ID is ``class << 4 | board``), name, length, sender."""

    frame_class: int
    name: str
    length: int
    sender: str
    signals: tuple[Signal, ...]


def _camel(name: str) -> str:
    return "".join(part.capitalize() for part in name.split("_"))


def _enum_choices(enum: type[CommandCode] | type[NackReason] | type[MarkerPhase]
                  | type[SessionReason] | type[RunEndReason] | type[Task]
                  ) -> tuple[tuple[int, str], ...]:
    return tuple(sorted({int(m): m.name for m in enum}.items()))


def _event_slots(header_bits: int, slots: int, wide: bool = False) -> tuple[Signal, ...]:
    """``Ev<i>`` (12-bit) or ``WEv<i>`` (24-bit, ``wide``) slots: delta, then address."""
    name, width, delta, empty = (("WEv", 24, 4, k.EMPTY_WIDE_SLOT) if wide
                                 else ("Ev", 12, 3, k.EMPTY_SLOT))
    out: list[Signal] = []
    for i in range(slots):
        at = header_bits + width * i
        out += [Signal(f"{name}{i}Delta", at, delta),
                Signal(f"{name}{i}Addr", at + delta, width - delta,
                       choices=((empty >> delta, "NONE"),))]
    return tuple(out)


def _answer_signals(opcode: int) -> tuple[Signal, ...]:
    """The ANSWER command's fields (SPEC.md §3.5.3): ``AnswerTask`` (bits 32..35), itself a
    multiplexer of the task's values in bits 36..63."""
    out = [Signal("AnswerTask", 32, 4, mux=f"m{opcode}M", mux_range=(opcode, opcode),
                  choices=tuple((t, ANSWER_LAYOUTS[t].name.upper())
                                for t in sorted(ANSWER_LAYOUTS)))]
    for task in sorted(ANSWER_LAYOUTS):
        lay = ANSWER_LAYOUTS[task]
        for i, (name, unit) in enumerate(zip(lay.signal_names(), lay.unit_names(),
                                             strict=True)):
            out.append(Signal(name, 36 + i * lay.bits, lay.bits, unit, mux=f"m{task}",
                              mux_range=(task, task), scale=lay.scale, signed=lay.signed,
                              multiplexer="AnswerTask"))
    return tuple(out)


def _payload_signals(fields: tuple[tuple[str, int, int], ...], fd: bool,
                     reasons: tuple[tuple[int, str], ...]) -> list[Signal]:
    """Signals of a session-record payload's fields: FD from bit 16 (after the sequence and
    chunk bytes); classic in the chunk (mux value) holding each field, from bit 8."""
    out = []
    for name, off, n in fields:
        choices = reasons if name in ("Reason", "Task") else ()
        start = 16 + 8 * off if fd else 8 + 8 * (off % CLASSIC_CHUNK)
        out.append(Signal(name, start, 8 * n, mux="m0" if fd else f"m{off // CLASSIC_CHUNK}",
                          choices=choices, float32=name in ("SnrDb", "Tolerance")))
    return out


def _tail_bytes(name: str, head: int, longest: int, fd: bool) -> list[Signal]:
    """Raw bytes (``name``0 in chunk 0, ``name`` in the chunks after) of a session record's
    variable part after its ``head`` fixed bytes, for payloads up to ``longest`` bytes: a DBC
    has no string or array signals."""
    size = FD_CHUNK if fd else CLASSIC_CHUNK
    last = -(-longest // size) - 1
    first_bits = min((size - head) * 8, 64)
    out = []
    if first_bits > 0:
        out.append(Signal(f"{name}0", 16 + 8 * head if fd else 8 + 8 * head, first_bits,
                          mux="m0"))
    out.append(Signal(name, 16 if fd else 8, 64 if fd else 8 * CLASSIC_CHUNK, mux="m1",
                      mux_range=(1, last)))
    return out


def _session_messages(fd: bool, seq: Signal) -> tuple[Message, ...]:
    """SKIN_SESSION, SKIN_STIMULUS, SKIN_RUN_END, SKIN_SUITE and SKIN_TASK (SPEC.md §5.8): a
    session record's payload in chunks, multiplexed by ``Chunk`` (classic byte 0 bits 7..4,
    FD byte 1). A name's bytes are shown raw (``NameBytes``), and a TASK's unit and classes
    (``TailBytes``): a DBC has no string or array signals."""
    length = FD_FRAME_BYTES if fd else 8
    chunk = Signal("Chunk", 8, 8, mux="M") if fd else Signal("Chunk", 4, 4, mux="M")
    session = Message(k.CLS_SESSION, "SKIN_SESSION", length, BOARD, (
        seq, chunk, *_payload_signals(SESSION_FIELDS, fd, _enum_choices(SessionReason))))
    run_end = Message(k.CLS_RUN_END, "SKIN_RUN_END", length, BOARD, (
        seq, chunk, *_payload_signals(RUN_END_FIELDS, fd, _enum_choices(RunEndReason))))
    head = _payload_signals((("StimulusId", 0, 4), ("NameLength", 4, 1)), fd, ())
    stimulus = Message(k.CLS_STIMULUS, "SKIN_STIMULUS", length, BOARD, (
        seq, chunk, *head,
        *_tail_bytes("NameBytes", STIMULUS_HEAD, STIMULUS_HEAD + MAX_NAME_BYTES, fd)))
    suite = Message(k.CLS_SUITE, "SKIN_SUITE", length, BOARD, (
        seq, chunk, *_payload_signals(SUITE_FIELDS, fd, ()),
        *_tail_bytes("NameBytes", SUITE_HEAD, SUITE_HEAD + 2 * MAX_SUITE_NAME_BYTES, fd)))
    task = Message(k.CLS_TASK, "SKIN_TASK", length, BOARD, (
        seq, chunk, *_payload_signals(TASK_FIELDS, fd, tuple(
            (t, ANSWER_LAYOUTS[t].name.upper()) for t in sorted(ANSWER_LAYOUTS))),
        *_tail_bytes("TailBytes", TASK_HEAD, TASK_HEAD + MAX_UNIT_BYTES + 4 * MAX_CLASSES,
                     fd)))
    return session, stimulus, run_end, suite, task


def messages(fd: bool) -> tuple[Message, ...]:
    """Every frame type of the classic (``fd`` False) or CAN FD layout, as SPEC.md §5 and
    (SKIN_WIDE_EVENTS, sent only by boards of more than 338 channels) §9.2."""
    seq = Signal("Seq", 0, 8 if fd else 4)
    decision = int(CommandCode.DECISION)
    answer = int(CommandCode.ANSWER)
    grip = int(CommandCode.GRIP)
    command = Message(k.CLS_COMMAND, "SKIN_COMMAND", 8, HOST, (
        seq, Signal("Opcode", 8, 8, mux="M", choices=_enum_choices(CommandCode)),
        Signal("Token", 16, 16),
        Signal("Arg", 32, 32, mux="m1", mux_range=(1, decision - 1)),
        Signal("DecisionStimulusId", 32, 24, mux=f"m{decision}", mux_range=(decision, decision)),
        Signal("DecisionConfidence", 56, 8, mux=f"m{decision}", mux_range=(decision, decision),
               choices=((CONFIDENCE_STEPS + 1, "NONE"),)),
        *_answer_signals(answer),
        Signal("GripN", 32, 32, "N", mux=f"m{grip}", mux_range=(grip, grip),
               float32=True)))
    ack = Message(k.CLS_ACK, "SKIN_ACK", 6, BOARD, (
        seq, Signal("Ok", 8, 1), Signal("AckSeq", 9, 7),
        Signal("Opcode", 16, 8, choices=_enum_choices(CommandCode)),
        Signal("Reason", 24, 8, choices=_enum_choices(NackReason)), Signal("Token", 32, 16)))
    phase_choices = _enum_choices(MarkerPhase)
    if fd:
        sync = Message(k.CLS_SYNC, "SKIN_SYNC", 12, BOARD, (
            seq, Signal("Epoch", 8, 3), Signal("Reserved", 11, 1), Signal("Version", 12, 4),
            Signal("StepUs", 16, 16, "us"), Signal("BaseSteps", 32, 48)))
        status = Message(k.CLS_STATUS, "SKIN_STATUS", STATUS_LEN_FD, BOARD, (
            seq, Signal("Running", 8, 1), Signal("Version", 12, 4),
            Signal("TimeUs", 16, 48, "us"),
            *(Signal(_camel(name), 64 + 32 * i, 32) for i, name in enumerate(STATUS_WORDS))))
        marker = Message(k.CLS_MARKER, "SKIN_MARKER", 12, BOARD, (
            seq, Signal("Phase", 8, 8, choices=phase_choices), Signal("TimeUs", 16, 48, "us"),
            Signal("StimulusId", 64, 32)))
        events = Message(k.CLS_EVENTS, "SKIN_EVENTS", k.EVENTS_LEN_FD, BOARD, (
            seq, Signal("Epoch", 8, 3), Signal("Count", 11, 6), Signal("Offset", 17, 15),
            *_event_slots(32, k.FD_MAX_EVENTS)))
        wide = Message(k.CLS_WIDE, "SKIN_WIDE_EVENTS", k.EVENTS_LEN_FD, BOARD, (
            seq, Signal("Epoch", 8, 3), Signal("Count", 11, 6), Signal("Offset", 17, 15),
            *_event_slots(32, k.FD_MAX_WIDE, wide=True)))
    else:
        sync = Message(k.CLS_SYNC, "SKIN_SYNC", 8, BOARD, (
            seq, Signal("Epoch", 4, 3), Signal("Reserved", 7, 1),
            Signal("StepUs", 8, 16, "us"), Signal("BaseSteps", 24, 40)))
        muxed = [Signal("TimeUs", 8, 48, "us", "m0"), Signal("Running", 56, 1, mux="m0"),
                 Signal("Version", 60, 4, mux="m0")]
        for mux, (u32, u24) in enumerate(CLASSIC_STATUS_MUX, start=1):
            muxed.append(Signal(_camel(u32), 8, 32, mux=f"m{mux}"))
            if u24 is not None:
                muxed.append(Signal(_camel(u24), 40, 24, mux=f"m{mux}"))
        status = Message(k.CLS_STATUS, "SKIN_STATUS", 8, BOARD, (
            seq, Signal("Mux", 4, 4, mux="M"), *muxed))
        marker = Message(k.CLS_MARKER, "SKIN_MARKER", 8, BOARD, (
            seq, Signal("Phase", 4, 4, choices=phase_choices), Signal("TimeUs", 8, 40, "us"),
            Signal("StimulusId", 48, 16)))
        events = Message(k.CLS_EVENTS, "SKIN_EVENTS", k.EVENTS_LEN_CLASSIC, BOARD, (
            seq, Signal("Epoch", 4, 3), Signal("Offset", 7, 9),
            *_event_slots(16, k.CLASSIC_MAX_EVENTS)))
        wide = Message(k.CLS_WIDE, "SKIN_WIDE_EVENTS", k.EVENTS_LEN_CLASSIC, BOARD, (
            seq, Signal("Epoch", 4, 3), Signal("Offset", 7, 9),
            *_event_slots(16, k.CLASSIC_MAX_WIDE, wide=True)))
    return (command, ack, sync, status, marker, events, wide,
            *_session_messages(fd, seq))


def dbc_text(board_id: int = 0, fd: bool = False) -> str:
    """The DBC of board ``board_id`` (0..15), classic CAN or (``fd``) CAN FD."""
    if not 0 <= int(board_id) <= 15:
        raise ProtocolError(f"CAN board id {board_id} is outside 0..15: give 0..15")
    layout = "CAN FD" if fd else "classic CAN"
    lines = [f'VERSION "skinhil protocol {PROTOCOL_VERSION} ({layout}, board {board_id})"', "",
             "NS_ :", "", "BS_:", "", f"BU_: {BOARD} {HOST}", ""]
    values: list[str] = []
    mux_ranges: list[str] = []
    value_types: list[str] = []
    msgs = messages(fd)
    for m in msgs:
        ident = can_id(m.frame_class, board_id)
        lines.append(f"BO_ {ident} {m.name}: {m.length} {m.sender}")
        receiver = HOST if m.sender == BOARD else BOARD
        for s in m.signals:
            mux = f" {s.mux}" if s.mux else ""
            if s.float32:
                low, top = "-3.4e+38", "3.4e+38"
            elif s.signed:
                low = f"{-(1 << (s.bits - 1)) * s.scale:g}"
                top = f"{((1 << (s.bits - 1)) - 1) * s.scale:g}"
            elif s.scale == 1.0:
                low, top = "0", str((1 << s.bits) - 1)
            else:
                low, top = "0", f"{((1 << s.bits) - 1) * s.scale:g}"
            lines.append(f" SG_ {s.name}{mux} : {s.start}|{s.bits}@1{'-' if s.signed else '+'}"
                         f' ({s.scale:g},0) [{low}|{top}] "{s.unit}" {receiver}')
            if s.float32:
                value_types.append(f"SIG_VALTYPE_ {ident} {s.name} : 1;")
            if s.mux_range is not None:
                mux_name = s.multiplexer or next(x.name for x in m.signals if x.mux == "M")
                mux_ranges.append(f"SG_MUL_VAL_ {ident} {s.name} {mux_name} "
                                  f"{s.mux_range[0]}-{s.mux_range[1]};")
            if s.choices:
                pairs = " ".join(f'{v} "{n}"' for v, n in s.choices)
                values.append(f"VAL_ {ident} {s.name} {pairs} ;")
        lines.append("")
    lines.append(f'CM_ "skinhil wire protocol version {PROTOCOL_VERSION}, {layout}, board id '
                 f"{board_id} (ID = class << 4 | board id). Every frame type has the length "
                 "given here. Event slots after the last event hold address 511 (NONE). "
                 "A COMMAND of opcode DECISION carries DecisionStimulusId and "
                 "DecisionConfidence (0..254 = confidence x 254; 255 NONE) instead of Arg; "
                 "one of opcode ANSWER carries AnswerTask and the task's values; "
                 "one of opcode GRIP carries GripN (N, IEEE-754 binary32). "
                 'Layout: protocols/SPEC.md";')
    if fd:
        lines.append('BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN",'
                     + ",".join(['"reserved"'] * 12) + ',"StandardCAN_FD","ExtendedCAN_FD";')
        lines.append('BA_DEF_DEF_ "VFrameFormat" "StandardCAN_FD";')
        lines += [f'BA_ "VFrameFormat" BO_ {can_id(m.frame_class, board_id)} {_FD_FORMAT};'
                  for m in msgs]
    lines += values
    lines += value_types
    lines += mux_ranges
    return "\n".join(lines) + "\n"
