"""The conformance vectors of protocols/conformance.json (SPEC.md §11), built here.

Each case is input bytes of a serial stream (SPEC.md §2-§4, §9, §3.7) and what a decoder that
follows SPEC.md §6-§7 must output: the events, the records and every counter. The inputs are
made with the encoders and by hand (damaged, reordered, repeated packets: the cases of
tests/test_protocol_refusals.py, test_protocol_corruption.py and test_protocol_fuzz.py); the
expected outputs are written here from the SPEC's rules, not taken from a decoder, so the
file checks the reference decoder as much as any other (tests/test_conformance.py).
"""

from __future__ import annotations

import json
import math
import struct
from typing import Any

import numpy as np
from protocol_examples import (
    ACK,
    ANSWERS,
    BURST,
    COMMAND,
    DECISION,
    EVENTS,
    MARKER,
    SESSION,
    STATUS,
    SUITE_RECORDS,
    TABLE,
    TASK_CLASSES,
    framed,
)

from protocols import (
    ANSWER_SCALE,
    Ack,
    Answer,
    Command,
    CommandCode,
    Decision,
    NackReason,
    RunEnd,
    RunEndReason,
    SerialEncoder,
    Status,
    SuiteEntry,
    Task,
)
from skinhil.events import make_events

COUNTERS = ("frames_ok", "crc_errors", "malformed", "resyncs", "bytes_discarded", "seq_gaps",
            "frames_lost", "duplicates", "late_frames", "events_decoded", "events_untimed",
            "events_lost", "events_lost_reported", "syncs", "command_seq_gaps", "commands_lost")
"""The counters of SPEC.md §7 a serial decoder keeps, in the file's order."""


def record_json(rec: Any) -> dict[str, Any]:
    """A record as the file writes it: its type and wire fields (enums and flags as
    integers, a SET_SNR argument or SNR as a number or "inf", a DECISION's confidence as its
    byte 0..255, an ANSWER's values as signed integers of its task's steps); a STATUS has
    no ``link_events`` (the decoder's own use, §7)."""
    if isinstance(rec, Answer):  # values in wire steps (SPEC.md §3.5.3)
        task = int(rec.task)
        scale = ANSWER_SCALE.get(task, 1.0)
        return {"type": "ANSWER", "token": rec.token, "task": task,
                "values": [round(v / scale) for v in rec.values]}
    if isinstance(rec, Decision):
        conf = 255 if rec.confidence is None else round(rec.confidence * 254)
        return {"type": "DECISION", "token": rec.token, "stimulus_id": rec.stimulus_id,
                "confidence": conf}
    names = {"Status": "STATUS", "Marker": "MARKER", "Command": "COMMAND", "Ack": "ACK",
             "Session": "SESSION", "StimulusEntry": "STIMULUS", "RunEnd": "RUN_END",
             "SuiteEntry": "SUITE", "TaskEntry": "TASK"}
    out: dict[str, Any] = {"type": names[type(rec).__name__]}
    for k, v in vars(rec).items():
        if isinstance(v, bool):
            v = int(v)
        elif isinstance(v, float):
            v = "inf" if math.isinf(v) and v > 0 else "-inf" if math.isinf(v) else v
        elif isinstance(v, int):
            v = int(v)
        elif isinstance(v, tuple):  # a TASK's classes: a JSON list
            v = list(v)
        out[k] = v
    return out


def _events(ev: np.ndarray) -> list[list[int]]:
    return [[int(t), int(a)] for t, a in zip(ev["t"], ev["addr"], strict=True)]


def _pkt(b0: int, seq: int, payload: bytes) -> bytes:
    """One packet of body ``b0, seq, payload`` with a good CRC."""
    return framed(bytes([b0, seq]) + payload)


def _sync(seq: int, base: int, epoch: int = 0, version: int = 3, step: int = 100) -> bytes:
    return _pkt(1 << 5 | epoch, seq, bytes([version]) + struct.pack("<H", step)
                + base.to_bytes(6, "little"))


def _words(seq: int, offset: int, items: list[tuple[int, int]], epoch: int = 0) -> bytes:
    """An EVENTS packet of address words (delta, address)."""
    body = struct.pack("<H", offset) + b"".join(struct.pack("<H", a << 7 | d) for d, a in items)
    return _pkt(epoch, seq, body)


def _status(seq: int, t_us: int, generated: int, sent: int, link_events: int,
            dropped: int = 0) -> bytes:
    words = [generated, sent, dropped, generated - sent - dropped, 0, 0, dropped, 0, 0,
             link_events, 0, 0, 0]
    return _pkt(2 << 5 | 1, seq, t_us.to_bytes(6, "little")
                + struct.pack("<13I", *[w & 0xFFFFFFFF for w in words]))


def _status_json(t_us: int, generated: int, sent: int, dropped: int = 0) -> dict[str, Any]:
    return record_json(Status(t_us, generated, sent, dropped, generated - sent - dropped, 0, 0,
                              True, dropped_fifo_full=dropped))


def _case(name: str, spec: str, what: str, data: bytes, events: list[list[int]] | None = None,
          records: list[dict[str, Any]] | None = None, **counters: int) -> dict[str, Any]:
    unknown = set(counters) - set(COUNTERS)
    assert not unknown, unknown
    return {"name": name, "spec": spec, "description": what, "input": data.hex(),
            "events": events or [], "records": records or [],
            "counters": {c: counters.get(c, 0) for c in COUNTERS}}


def _four() -> tuple[bytes, list[list[int]]]:
    """SPEC §4's SYNC and EVENTS packets (seq 0, 1) and their four events."""
    return SerialEncoder().events(EVENTS, 1000), _events(EVENTS)


def cases() -> list[dict[str, Any]]:
    """Every conformance case, in the file's order."""
    four, four_ev = _four()
    sync, events_pkt = four[:four.index(0) + 1], four[four.index(0) + 1:]
    ev2 = _words(2, 10, [(0, 7)])  # seq 2: channel 7 at step 10 (1000 µs)
    out = [
        _case("events", "§3.1, §3.2, §4", "A SYNC, then an EVENTS packet of four address "
              "words (SPEC §4).", four, four_ev, frames_ok=2, syncs=1, events_decoded=4),
        _case("bitmap", "§3.1, §4", "A SYNC (base 2), then an EVENTS packet holding one "
              "bitmap of 25 channels at 200 µs.", SerialEncoder().events(BURST, 1000),
              _events(BURST), frames_ok=2, syncs=1, events_decoded=25),
    ]
    enc = SerialEncoder()
    records = (enc.status(STATUS) + enc.marker(MARKER) + enc.ack(ACK))
    out.append(_case(
        "records", "§3.3, §3.4, §3.6, §7", "A STATUS, a MARKER and an ACK (seq 0, 1, 2): the "
        "status's events_dropped is the board's own loss.", records, [],
        [record_json(STATUS), record_json(MARKER), record_json(ACK)], frames_ok=3,
        events_lost_reported=STATUS.events_dropped))
    host = SerialEncoder()
    cmds = host.command(COMMAND) + host.command(DECISION) + host.command(
        Command(7, CommandCode.QUERY_SESSION))
    out.append(_case(
        "commands", "§3.5, §3.5.1", "Three COMMANDs of a host (SET_SNR 10 dB, a DECISION of "
        "stimulus 3 at confidence 127/254, QUERY_SESSION).", cmds, [],
        [record_json(COMMAND), record_json(DECISION),
         record_json(Command(7, CommandCode.QUERY_SESSION, 0))], frames_ok=3))
    host = SerialEncoder()
    answers = (*ANSWERS, Answer(0x123A, Task.CLASSIFICATION, (12,)), Answer(0x123B, 7, (5,)))
    out.append(_case(
        "answers", "§3.5.3", "ANSWERs of a host: LOCALISATION (1.25, -2.5) mm, FORCE 0.3 N, "
        "SLIP, VIBRATION 100 Hz, CLASSIFICATION of stimulus 12, and one of the reserved task "
        "7 (its 28-bit field as its one value: the board NACKs it UNKNOWN_TASK).",
        b"".join(host.command(a) for a in answers), [], [record_json(a) for a in answers],
        frames_ok=6))
    host, board = SerialEncoder(), SerialEncoder()
    grip = Command(0x1240, CommandCode.GRIP, 0.75)
    nack = Ack(0x1241, CommandCode.GRIP, False, NackReason.GRIP_LIMIT)
    out.append(_case(
        "grip", "§3.5.6, §3.6", "A host's GRIP of 0.75 N (binary32) and a board's NACK of "
        "another GRIP for reason 11 GRIP_LIMIT (their own sequence numbers, 0 each).",
        host.command(grip) + board.ack(nack), [], [record_json(grip), record_json(nack)],
        frames_ok=2))
    enc = SerialEncoder()
    end = RunEnd(t_us=20_000_000, reason=RunEndReason.DURATION)
    sess = b"".join(enc.session_record(r) for r in (SESSION, *TABLE, end))
    out.append(_case(
        "session", "§3.7", "A SESSION, its two STIMULUS rows (ids 0 and 10) and a RUN_END "
        "(duration over).", sess, [], [record_json(r) for r in (SESSION, *TABLE, end)],
        frames_ok=4))
    suite = (*SUITE_RECORDS, TASK_CLASSES, SuiteEntry())
    out.append(_case(
        "suite", "§3.7", "The SUITE and TASK of a suite case (FORCE within 0.05 N), a TASK with "
        "classes (VIBRATION: 50, 100, 200, 300 Hz) and the SUITE of a board playing no suite.",
        b"".join(enc.session_record(r) for r in suite), [], [record_json(r) for r in suite],
        frames_ok=4))
    wide = SerialEncoder(n_channels=15_730)
    wide_ev = make_events([0, 0, 300, 900], [5, 15_000, 337, 12_810])
    out.append(_case(
        "wide-events", "§9.1", "A version-4 SYNC and a WIDE_EVENTS packet (a 32x32 skin).",
        wide.events(wide_ev, 1000), _events(wide_ev), frames_ok=2, syncs=1, events_decoded=4))
    # -- damage ---------------------------------------------------------------------------
    bad = bytearray(events_pkt)
    bad[6] ^= 0x10  # one bit of an event word
    out.append(_case(
        "crc-error", "§6 rules 2-4", "A SYNC, an EVENTS packet with one bit flipped (its CRC "
        "fails; no suffix of it is a packet), then a good EVENTS packet (seq 2).",
        sync + bytes(bad) + ev2, [[1000, 7]], frames_ok=2, crc_errors=1,
        bytes_discarded=len(events_pkt) - 1, seq_gaps=1, frames_lost=1, syncs=1,
        events_decoded=1))
    phase2 = _pkt(3 << 5, 0, (250_000).to_bytes(6, "little") + struct.pack("<IB", 3, 2))
    out.append(_case(
        "malformed-marker-phase", "§3.4, §6 rule 3", "A MARKER of phase 2 (good CRC): "
        "malformed, its bytes discarded, no record.", phase2, malformed=1,
        bytes_discarded=len(phase2) - 1))
    reserved = _pkt(7 << 5 | 5, 0, bytes(7))
    out.append(_case(
        "malformed-reserved-kind", "§3.7, §6 rule 2", "A type-7 packet of the reserved kind "
        "5: malformed.", reserved, malformed=1, bytes_discarded=len(reserved) - 1))
    down = _words(1, 0, [(0, 17), (0, 5)])
    out.append(_case(
        "malformed-descending-channels", "§3.1", "After a SYNC, an EVENTS packet whose "
        "channels of one step do not ascend (17, then 5 at delta 0): malformed, no event.",
        sync + down, frames_ok=1, syncs=1, malformed=1, bytes_discarded=len(down) - 1))
    empty = _pkt(0, 1, struct.pack("<H", 0))
    out.append(_case(
        "malformed-empty-events", "§3.1", "An EVENTS packet without items: malformed.",
        sync + empty, frames_ok=1, syncs=1, malformed=1, bytes_discarded=len(empty) - 1))
    v5 = _sync(0, 0, version=5)
    out.append(_case(
        "malformed-sync-version", "§1, §3.2", "A SYNC of version 5: malformed; the events "
        "after it have no time base.", v5 + _words(1, 0, [(0, 5)]), frames_ok=1, malformed=1,
        bytes_discarded=len(v5) - 1, events_untimed=1))
    out.append(_case(
        "gap", "§6 rule 4", "SYNC (seq 0), EVENTS (seq 1), EVENTS (seq 4): one gap of two "
        "packets; the time base holds (gap < 32).", sync + events_pkt + _words(4, 10, [(0, 7)]),
        [*four_ev, [1000, 7]], frames_ok=3, syncs=1, seq_gaps=1, frames_lost=2,
        events_decoded=5))
    out.append(_case(
        "duplicate", "§6 rule 4", "The EVENTS packet sent twice: the repeat (same sequence "
        "number) is ignored.", four + events_pkt, four_ev, frames_ok=2, syncs=1,
        duplicates=1, events_decoded=4))
    late = _words(2, 10, [(0, 7)]) + _words(3, 11, [(0, 8)])
    out.append(_case(
        "late", "§6 rule 4, §10", "Packets seq 0 (SYNC), 2, 3, then seq 1 (two behind the "
        "last): late, dropped, its four events untimed; the time base stays.",
        sync + late + events_pkt + _words(4, 12, [(0, 9)]),
        [[1000, 7], [1100, 8], [1200, 9]], frames_ok=4, syncs=1, seq_gaps=1, frames_lost=1,
        late_frames=1, events_untimed=4, events_decoded=3))
    junk = bytes(range(1, 24))
    out.append(_case(
        "resync-noise", "§6 rule 3", "23 noise bytes (no zero) glued to the front of a SYNC: "
        "one CRC error, the SYNC found by the suffix search, the noise discarded.",
        junk + sync + events_pkt, four_ev, frames_ok=2, crc_errors=1, resyncs=1,
        bytes_discarded=len(junk), syncs=1, events_decoded=4))
    cut = bytes(bad[:-1])  # the damaged packet without its delimiter
    out.append(_case(
        "lost-delimiter", "§6 rule 3", "A SYNC, a damaged EVENTS packet whose delimiter was "
        "lost, then a good EVENTS packet (seq 2) in the same candidate: resynchronised.",
        sync + cut + ev2, [[1000, 7]], frames_ok=2, crc_errors=1, resyncs=1,
        bytes_discarded=len(cut), seq_gaps=1, frames_lost=1, syncs=1, events_decoded=1))
    zeros = events_pkt[:-1] + b"\x01\x01" + b"\x00"
    out.append(_case(
        "appended-zeros", "§2", "Two 0x01 bytes before the EVENTS packet's delimiter decode "
        "to two appended zero bytes: the CRC fails (never an address-0 event).",
        sync + zeros, frames_ok=1, syncs=1, crc_errors=1, bytes_discarded=len(zeros) - 1))
    out.append(_case(
        "idle-zeros", "§2", "Extra 0x00 bytes between packets: idle, never counted.",
        b"\x00\x00" + sync + b"\x00" * 3 + events_pkt + b"\x00", four_ev, frames_ok=2,
        syncs=1, events_decoded=4))
    long = bytes([1 + i % 250 for i in range(1100)]) + b"\x00"
    out.append(_case(
        "oversize-candidate", "§6 rule 3", "1100 bytes without a delimiter (no packet inside): "
        "one CRC error; all are discarded.", long, crc_errors=1, bytes_discarded=1100))
    out.append(_case(
        "untimed", "§6 rule 5", "An EVENTS packet before any SYNC: counted, its events "
        "untimed (a decoder never guesses a time).", events_pkt, frames_ok=1,
        events_untimed=4))
    out.append(_case(
        "epoch-mismatch", "§1, §6 rule 5", "After a SYNC of epoch 0, an EVENTS packet of "
        "epoch 1: untimed.", sync + _words(1, 0, [(0, 5)], epoch=1), frames_ok=2, syncs=1,
        events_untimed=1))
    out.append(_case(
        "gap-loses-time-base", "§6 rule 4", "SYNC (seq 0), then EVENTS seq 40 (a gap of 39 "
        "≥ 32: the time base is lost), untimed; a SYNC (seq 41, base 100) restores it.",
        sync + _words(40, 0, [(0, 5)]) + _sync(41, 100, epoch=1)
        + _words(42, 1, [(0, 6)], epoch=1), [[10_100, 6]], frames_ok=4, syncs=2, seq_gaps=1,
        frames_lost=39, events_untimed=1, events_decoded=1))
    out.append(_case(
        "sync-jump", "§6 rule 5", "SYNC base 0, a SYNC of base 2^47 (a jump: the time base "
        "is invalid), EVENTS untimed, then a SYNC of base 10 continuing the first: valid.",
        _sync(0, 0) + _sync(1, 1 << 47, epoch=1) + _words(2, 0, [(0, 5)], epoch=1)
        + _sync(3, 10, epoch=2) + _words(4, 0, [(0, 6)], epoch=2), [[1000, 6]], frames_ok=5,
        syncs=3, events_untimed=1, events_decoded=1))
    out.append(_case(
        "events-lost", "§7", "STATUS (link_events 0), SYNC, EVENTS of 4 events (lost: seq "
        "2 missing), EVENTS of 1, STATUS (link_events 5): events_lost = 4.",
        _status(0, 0, 0, 0, 0) + _sync(1, 0) + _words(3, 10, [(0, 7)])
        + _status(4, 2000, 5, 5, 5),
        [[1000, 7]], [_status_json(0, 0, 0), _status_json(2000, 5, 5)], frames_ok=4,
        syncs=1, seq_gaps=1, frames_lost=1, events_decoded=1, events_lost=4))
    out.append(_case(
        "status-unwrap", "§1, §7", "Two STATUS packets whose events_generated and "
        "events_sent wrap past 2^32: unwrapped to 2^32 + 5.",
        _status(0, 1000, 2**32 - 5, 2**32 - 5, 0) + _status(1, 2000, 5, 5, 0), [],
        [_status_json(1000, 2**32 - 5, 2**32 - 5), _status_json(2000, 2**32 + 5, 2**32 + 5)],
        frames_ok=2))
    marker = _pkt(3 << 5 | 0x1F, 0, (250_000).to_bytes(6, "little") + struct.pack("<IB", 3, 0))
    ack = _pkt(5 << 5 | 0x1E, 1, struct.pack("<HBB", 0x1234, 3, 3))
    out.append(_case(
        "reserved-bits-ignored", "§1, §3", "A MARKER with byte 0 bits 4..0 set and an ACK "
        "with bits 4..1 set (reserved: ignored, the packets decode; the ACK's ok bit is 0).",
        marker + ack, [], [record_json(MARKER), record_json(ACK)], frames_ok=2))
    host = SerialEncoder()
    mixed = (sync + host.command(Command(1, CommandCode.PING)) + events_pkt
             + _pkt(4 << 5, 5, struct.pack("<HBI", 3, 7, 0)))
    out.append(_case(
        "command-sequence-apart", "§1, §6 rule 4", "Board packets (seq 0, 1) with a host's "
        "COMMANDs (its own seq 0, then 5) among them: the board's sequence has no gap; the "
        "host's has one of four.", mixed, four_ev,
        [record_json(Command(1, CommandCode.PING, 0)), record_json(Command(3, 7, 0))],
        frames_ok=4, syncs=1, events_decoded=4, command_seq_gaps=1, commands_lost=4))
    return out


def conformance_json() -> str:
    """The text of protocols/conformance.json."""
    doc = {
        "format": 1,
        "spec": "protocols/SPEC.md §11",
        "about": "Serial stream conformance vectors: feed 'input' (hex bytes) to a fresh "
                 "decoder in one piece; it must return 'events' ([t_us, addr], in order), "
                 "'records' (in order, wire fields; STATUS counters unwrapped) and end with "
                 "exactly 'counters' (SPEC.md §7).",
        "cases": cases(),
    }
    return json.dumps(doc, indent=1, ensure_ascii=False) + "\n"
