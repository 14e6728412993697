"""Units that look almost right but break the layout are refused and counted (SPEC.md §3, §5,
§6): an EVENTS body over 1,024 bytes, CAN frames longer than their layout, a MARKER phase
beyond END, and a host's COMMAND inside the board's stream never moving the board's sequence."""

from __future__ import annotations

import numpy as np
import pytest
from protocol_examples import framed

from protocols import (
    Ack,
    CanDecoder,
    CanEncoder,
    CanFrame,
    Command,
    CommandCode,
    Marker,
    MarkerPhase,
    SerialDecoder,
    SerialEncoder,
)
from skinhil.events import make_events


def sync_packet() -> bytes:
    """A SYNC packet (seq 0, epoch 0, base 0) of a fresh encoder."""
    return SerialEncoder().events(make_events([0], [1]), 100).split(b"\x00")[0] + b"\x00"


def test_events_body_over_1024_bytes_is_malformed() -> None:
    # words (3, delta 1), (4, delta 0), ...: the second has a zero byte, so COBS adds no
    # byte and a body of 1,026 bytes still fits in a candidate of at most 1,032
    items = [(3, 1), (4, 0)]
    for n_words, ok in ((510, True), (511, False)):  # bodies of 1,024 and 1,026 bytes
        words = b"".join(((items[i % 2][0] << 7) | items[i % 2][1]).to_bytes(2, "little")
                         for i in range(n_words))
        dec = SerialDecoder()
        got = dec.feed(sync_packet() + framed(bytes([0, 1, 0, 0]) + words))
        assert len(got.events) == (n_words if ok else 0)
        assert dec.counters.malformed == (0 if ok else 1)
        assert dec.counters.frames_ok == (2 if ok else 1)


def test_serial_marker_phase_beyond_end_is_malformed_only() -> None:
    good = SerialEncoder().marker(Marker(250_000, 3, MarkerPhase.END))
    body = bytes([3 << 5, 0]) + (250_000).to_bytes(6, "little") + (3).to_bytes(4, "little")
    for phase, ok in ((1, True), (2, False), (255, False)):
        dec = SerialDecoder()
        got = dec.feed(framed(body + bytes([phase])))
        assert len(got.records) == ok and dec.counters.frames_ok == ok
        assert dec.counters.malformed == (not ok)
    assert framed(body + bytes([1])) == good


@pytest.mark.parametrize("fd", [False, True])
def test_can_records_longer_than_their_layout_are_malformed(fd: bool) -> None:
    enc = CanEncoder(1, fd=fd)
    frames = enc.events(make_events([0], [7]), 100)[:1]  # the SYNC
    frames += enc.marker(Marker(100, 2, MarkerPhase.ONSET))
    frames += enc.ack(Ack(9, CommandCode.PING, True))
    for f in frames:
        dec = CanDecoder(1, fd=fd)
        dec.feed([f])
        assert dec.counters.frames_ok == 1 and dec.counters.malformed == 0
        longer = bytes(f.data) + bytes(16 - len(f.data) if fd else 8 - len(f.data))
        if longer == bytes(f.data):
            continue  # a classic 8-byte frame cannot be longer
        dec = CanDecoder(1, fd=fd)
        got = dec.feed([CanFrame(f.arbitration_id, longer, f.is_fd)])
        assert got.records == [] and dec.counters.malformed == 1, (f, len(longer))
        assert dec.counters.frames_ok == 0 and dec.counters.syncs == 0


def test_a_command_in_the_board_stream_keeps_the_board_sequence() -> None:
    """A host's COMMAND packet among the board's packets (a shared or looped-back line)
    counts in the command counters, never as board frames lost; the time base stays."""
    board = SerialEncoder()
    host = SerialEncoder()
    ev = make_events([0, 100, 2000, 2100], [1, 2, 3, 4])
    stream = board.events(ev[:2], 1000)
    stream += host.command(Command(5, CommandCode.PING, 0))
    for _ in range(40):  # the host's counter is far from the board's
        host.command(Command(5, CommandCode.PING, 0))
    stream += host.command(Command(6, CommandCode.PING, 0))
    stream += board.events(ev[2:], 3000)
    dec = SerialDecoder()
    got = dec.feed(stream)
    assert got.events["addr"].tolist() == [1, 2, 3, 4]
    assert [r.token for r in got.records] == [5, 6]
    c = dec.counters
    assert c.frames_lost == 0 and c.seq_gaps == 0 and c.events_untimed == 0
    assert c.command_seq_gaps == 1 and c.commands_lost == 40
    again = dec.feed(host.command(Command(7, CommandCode.PING, 0)))
    assert len(again.records) == 1
    dup = SerialDecoder()
    packet = SerialEncoder().command(Command(8, CommandCode.STOP, 0))
    assert len(dup.feed(packet + packet).records) == 1 and dup.counters.duplicates == 1


def test_empty_events_and_empty_bitmap_are_malformed() -> None:
    bitmap_word = ((511 << 7) | 0).to_bytes(2, "little")
    bodies = {"no item": b"", "empty bitmap": bitmap_word + bytes(43),
              "one bit": bitmap_word + b"\x01" + bytes(42)}
    for name, items in bodies.items():
        dec = SerialDecoder()
        got = dec.feed(sync_packet() + framed(bytes([0, 1, 0, 0]) + items))
        ok = name == "one bit"
        assert len(got.events) == ok and dec.counters.malformed == (not ok), name


def test_a_reordered_packet_costs_only_its_own_events() -> None:
    """UDP reordering (SPEC.md §10): a packet arriving after the next few is late: dropped and
    counted, with no 250-frame gap and no lost time base for the packets after it."""
    enc = SerialEncoder()
    packets = []
    for ms in range(12):
        ev = make_events(np.arange(3, dtype=np.int64) * 100 + ms * 1000, [1, 2, 3])
        packets += [p + b"\x00" for p in enc.events(ev, (ms + 1) * 1000).split(b"\x00") if p]
    order = list(range(len(packets)))
    order.insert(8, order.pop(4))  # packet 4 overtaken by 5..8
    dec = SerialDecoder()
    got = dec.feed(b"".join(packets[i] for i in order))
    c = dec.counters
    assert c.late_frames == 1 and c.frames_lost == 1 and c.seq_gaps == 1
    assert len(got.events) == 3 * (len(packets) - 2)  # all but the SYNC's and the late one's
    assert c.events_untimed == 3


@pytest.mark.parametrize("layout", ["serial", "canfd"])
def test_a_sync_whose_times_overflow_is_malformed(layout: str) -> None:
    """Base × step at or beyond 2^62 µs would give negative event times: refused."""
    for base, step, ok in ((2**48 - 1, 65535, False), ((1 << 62) // 65535 - 1, 65535, True)):
        if layout == "serial":
            dec = SerialDecoder()
            body = bytes([1 << 5, 0, 3]) + step.to_bytes(2, "little") + base.to_bytes(6, "little")
            dec.feed(framed(body))
        else:
            dec = CanDecoder(1, fd=True)
            data = bytes([0, 3 << 4]) + step.to_bytes(2, "little") + base.to_bytes(6, "little")
            dec.feed([CanFrame(0x31, data + bytes(2), True)])
        assert dec.counters.syncs == ok and dec.counters.malformed == (not ok), (base, step)


@pytest.mark.parametrize("fd", [False, True])
@pytest.mark.parametrize("late_by", [1, 9, 16, 17])
def test_a_late_copy_of_a_can_events_frame_is_a_duplicate(fd: bool, late_by: int) -> None:
    """Classic CAN's 4-bit sequence number repeats every 16 frames: a copy 9 or more frames
    late passes the sequence check, but its events do not follow the last one decoded, so it
    is dropped and counted as a duplicate (SPEC §6, CAN); the copy 16 late (same sequence
    number as the frame before it) and 17 late (the next number) included."""
    t = np.repeat(np.arange(0, 400), 3) * 100  # 3 events every step: no SYNC in between
    addr = np.tile([5, 40, 300], 400)
    ev = make_events(t, addr)
    enc = CanEncoder(board_id=2, fd=fd)
    frames = enc.events(ev, 40_000)
    events_frames = [i for i, f in enumerate(frames) if f.arbitration_id >> 4 == 6]
    assert len(events_frames) > late_by + 2
    k = events_frames[1]
    damaged = frames[:k + late_by + 1] + [frames[k]] + frames[k + late_by + 1:]
    clean = CanDecoder(board_id=2, fd=fd)
    want = clean.feed(frames).events
    dec = CanDecoder(board_id=2, fd=fd)
    got = dec.feed(damaged).events
    np.testing.assert_array_equal(got, want)
    assert len(want) == len(ev)
    assert dec.counters.duplicates == 1
