"""Round trips of the wire codecs: any event stream and any record comes back identical."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from protocol_examples import distinct_events, framed

from protocols import (
    Ack,
    Answer,
    CanDecoder,
    CanEncoder,
    Command,
    CommandCode,
    Decision,
    Marker,
    MarkerPhase,
    NackReason,
    SerialDecoder,
    SerialEncoder,
    Status,
    Task,
)
from protocols.records import CONFIDENCE_STEPS, DECISION_MAX_STIMULUS_ID
from skinhil.errors import ProtocolError
from skinhil.events import EVENT_DTYPE, make_events

STEP = 100
LAYOUTS = ("serial", "can", "canfd")
SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def canonical(ev: np.ndarray) -> np.ndarray:
    return ev[np.lexsort((ev["addr"], ev["t"]))]


WRAP_BITS = {"serial": 48, "can": 40, "canfd": 48}
"""Width of the SYNC time base (steps): a stream starting before the wrap crosses it."""


@st.composite
def event_streams(draw: st.DrawFn, wrap_bits: int) -> tuple[np.ndarray, list[int]]:
    """Sorted events with silences (up to ~2**20 steps), bursts (up to all 338 channels in a
    step), a start anywhere up to just before the time-base wrap (which the stream then
    crosses), and the t_end of each encoder call."""
    start = draw(st.sampled_from([0, 12345, (1 << wrap_bits) - 300]))
    t = start
    times: list[int] = []
    addrs: list[int] = []
    for i in range(draw(st.integers(1, 25))):
        if i:
            t += draw(st.one_of(st.integers(0, 12), st.integers(0, 2000),
                                st.integers(60_000, 1 << 20)))
        kind = draw(st.integers(0, 3))
        if kind == 0:
            chans = list(range(338))
        elif kind == 1:
            chans = sorted(draw(st.sets(st.integers(0, 337), min_size=20, max_size=60)))
        else:
            chans = draw(st.lists(st.integers(0, 337), min_size=1, max_size=6))
        times += [t] * len(chans)
        addrs += chans
    ends = sorted(set(draw(st.lists(st.integers(start, t), max_size=6))))
    ev = distinct_events(np.array(times, dtype=np.int64) * STEP, addrs)
    return ev, [e * STEP for e in ends if e > start] + [(t + 1) * STEP]


def encode(layout: str, ev: np.ndarray, ends: list[int], board: int = 0) -> list:
    enc = SerialEncoder() if layout == "serial" else CanEncoder(board, fd=layout == "canfd")
    out, lo = [], 0
    for end in ends:
        hi = int(np.searchsorted(ev["t"], end))
        out.append(enc.events(ev[lo:hi], end))
        lo = hi
    return out


def decode_all(layout: str, chunks: list, board: int = 0) -> tuple[np.ndarray, object]:
    dec = SerialDecoder() if layout == "serial" else CanDecoder(board, fd=layout == "canfd")
    parts = [dec.feed(c).events for c in chunks]
    return np.concatenate(parts) if parts else np.empty(0, EVENT_DTYPE), dec.counters


@pytest.mark.parametrize("layout", LAYOUTS)
@SETTINGS
@given(data=st.data(), cut_seed=st.integers(0, 2**32 - 1))
def test_events_round_trip(layout: str, data: st.DataObject, cut_seed: int) -> None:
    ev, ends = data.draw(event_streams(WRAP_BITS[layout]))
    out = encode(layout, ev, ends)
    rng = np.random.default_rng(cut_seed)
    if layout == "serial":
        data = b"".join(out)
        cuts = np.sort(rng.integers(0, len(data) + 1, rng.integers(0, 8)))
        chunks = [data[a:b] for a, b in zip([0, *cuts], [*cuts, len(data)], strict=True)]
    else:
        frames = [f for part in out for f in part]
        cuts = np.sort(rng.integers(0, len(frames) + 1, rng.integers(0, 5)))
        chunks = [frames[a:b] for a, b in zip([0, *cuts], [*cuts, len(frames)], strict=True)]
    got, counters = decode_all(layout, chunks)
    np.testing.assert_array_equal(got, canonical(ev))
    assert counters.events_decoded == len(ev)
    assert counters.frames_lost == 0 and counters.events_untimed == 0


def test_bitmap_chosen_only_when_smaller() -> None:
    """A full step costs one 45-byte bitmap, not 338 two-byte words; a sparse step words."""
    full = make_events(np.zeros(338, np.int64), np.arange(338))
    few = make_events(np.zeros(22, np.int64), np.arange(22))
    full_bytes = len(SerialEncoder().events(full, 100))
    few_bytes = len(SerialEncoder().events(few, 100))
    assert full_bytes < 2 * 60
    assert few_bytes > 2 * 22
    assert len(SerialDecoder().feed(SerialEncoder().events(full, 100)).events) == 338


def test_a_channel_twice_in_a_step_is_refused() -> None:
    """A channel spikes at most once per step (SPEC.md §3.1): the encoder refuses a repeat and
    the decoder counts a packet repeating a channel in a step (or out of ascending order, or
    a bitmap sharing its step) as malformed, events and all."""
    ev = make_events(np.zeros(30, np.int64), np.r_[np.arange(29), 5])
    with pytest.raises(ProtocolError, match="once per step"):
        SerialEncoder().events(ev, 100)
    sync = SerialEncoder().events(make_events([0], [1]), 100).split(b"\x00")[0] + b"\x00"
    words = {"repeat": [(5, 0), (5, 0)], "descending": [(9, 0), (5, 0)],
             "ascending": [(5, 0), (9, 0), (5, 1)]}
    for name, items in words.items():
        body = bytes([0, 1, 0, 0]) + b"".join(  # EVENTS, epoch 0, seq 1, offset 0
            ((a << 7) | d).to_bytes(2, "little") for a, d in items)
        dec = SerialDecoder()
        got = dec.feed(sync + framed(body))
        ok = name == "ascending"
        assert len(got.events) == (3 if ok else 0), name
        assert dec.counters.malformed == (0 if ok else 1), name


statuses = st.builds(
    Status, t_us=st.integers(0, 2**48 - 1), events_generated=st.integers(0, 2**32 - 1),
    events_sent=st.integers(0, 2**32 - 1), events_dropped=st.integers(0, 2**32 - 1),
    events_queued=st.integers(0, 2**24 - 1), late_ticks=st.integers(0, 2**24 - 1),
    rx_errors=st.integers(0, 2**24 - 1), running=st.booleans(),
    dropped_fifo_full=st.integers(0, 2**32 - 1), dropped_stopped=st.integers(0, 2**32 - 1),
    dropped_link_down=st.integers(0, 2**32 - 1))
markers = st.builds(Marker, t_us=st.integers(0, 2**40 - 1), stimulus_id=st.integers(0, 65535),
                    phase=st.sampled_from(MarkerPhase))
commands = st.one_of(
    st.builds(Command, token=st.integers(0, 65535),
              opcode=st.sampled_from([c for c in CommandCode
                                      if c not in (CommandCode.SET_SNR, CommandCode.DECISION,
                                                   CommandCode.ANSWER)]),
              arg=st.integers(0, 2**32 - 1)),
    st.builds(Command, token=st.integers(0, 65535), opcode=st.just(CommandCode.SET_SNR),
              arg=st.sampled_from([math.inf, 0.0, -5.5, 10.0, 42.25])))
decisions = st.builds(Decision, token=st.integers(0, 65535),
                      stimulus_id=st.integers(0, DECISION_MAX_STIMULUS_ID),
                      confidence=st.one_of(st.none(), st.integers(0, CONFIDENCE_STEPS).map(
                          lambda v: v / CONFIDENCE_STEPS)))
_tok = st.integers(0, 65535)
_i14 = st.integers(-(1 << 13), (1 << 13) - 1)
_u28 = st.integers(0, (1 << 28) - 1)
answers = st.one_of(  # values on the wire's steps: they come back exactly
    st.builds(lambda t, s: Answer(t, Task.CLASSIFICATION, (s,)), _tok,
              st.integers(0, DECISION_MAX_STIMULUS_ID)),
    st.builds(lambda t, x, y: Answer(t, Task.LOCALISATION, (x * 0.01, y * 0.01)), _tok, _i14,
              _i14),
    st.builds(lambda t, n: Answer(t, Task.FORCE, (n * 1e-6,)), _tok, _u28),
    st.builds(lambda t: Answer(t, Task.SLIP, ()), _tok),
    st.builds(lambda t, n: Answer(t, Task.VIBRATION, (n * 1e-3,)), _tok, _u28),
    st.builds(lambda t, k, n: Answer(t, k, (n,)), _tok, st.integers(5, 15), _u28))
acks = st.builds(Ack, token=st.integers(0, 65535), opcode=st.sampled_from(CommandCode),
                 ok=st.booleans(), reason=st.sampled_from(NackReason))


@pytest.mark.parametrize("layout", LAYOUTS)
@SETTINGS
@given(records=st.lists(st.one_of(markers, commands, decisions, answers, acks), max_size=8),
       status=statuses,
       where=st.integers(0, 8))
def test_records_round_trip(layout: str, records: list, status: Status, where: int) -> None:
    """Records in any order, with one status (a status stream is checked for unwrapping in
    test_status_counters_unwrap_across_modulo: counters only make sense counting up)."""
    records.insert(min(where, len(records)), status)
    enc = SerialEncoder() if layout == "serial" else CanEncoder(5, fd=layout == "canfd")
    host = SerialEncoder() if layout == "serial" else CanEncoder(5, fd=layout == "canfd")
    dec = SerialDecoder() if layout == "serial" else CanDecoder(5, fd=layout == "canfd")
    got = []
    for rec in records:  # commands come from a host: their own sequence numbers (SPEC.md §6)
        method = {Status: enc.status, Marker: enc.marker, Command: host.command,
                  Decision: host.command, Answer: host.command, Ack: enc.ack}[type(rec)]
        got += dec.feed(method(rec)).records
    assert got == records
    assert dec.counters.frames_lost == 0


@pytest.mark.parametrize("layout", LAYOUTS)
@SETTINGS
@given(token=st.integers(0, 65535), stimulus_id=st.integers(0, DECISION_MAX_STIMULUS_ID),
       confidence=st.floats(0.0, 1.0))
def test_decision_confidence_travels_to_the_nearest_step(layout: str, token: int,
                                                         stimulus_id: int,
                                                         confidence: float) -> None:
    """Any confidence in 0..1 comes back within half a step (1/508) of what was sent."""
    host = SerialEncoder() if layout == "serial" else CanEncoder(5, fd=layout == "canfd")
    dec = SerialDecoder() if layout == "serial" else CanDecoder(5, fd=layout == "canfd")
    (got,) = dec.feed(host.command(Decision(token, stimulus_id, confidence))).records
    assert isinstance(got, Decision) and got.opcode == CommandCode.DECISION
    assert (got.token, got.stimulus_id) == (token, stimulus_id)
    assert got.confidence is not None
    assert abs(got.confidence - confidence) <= 0.5 / CONFIDENCE_STEPS + 1e-12


@pytest.mark.parametrize("layout", LAYOUTS)
def test_bad_decisions_raise_protocol_error(layout: str) -> None:
    host = SerialEncoder() if layout == "serial" else CanEncoder(fd=layout == "canfd")
    with pytest.raises(ProtocolError, match="does not fit 24"):
        host.command(Decision(1, DECISION_MAX_STIMULUS_ID + 1))
    for bad in (-0.01, 1.5, math.nan):
        with pytest.raises(ProtocolError, match="outside 0..1"):
            host.command(Decision(1, 3, bad))
    with pytest.raises(ProtocolError, match="protocols.Decision"):
        host.command(Command(1, CommandCode.DECISION, 3))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_bad_answers_raise_protocol_error(layout: str) -> None:
    """Values outside a task's field, or a wrong count of them, are refused by the encoder."""
    host = SerialEncoder() if layout == "serial" else CanEncoder(fd=layout == "canfd")
    for bad in (Answer(1, Task.LOCALISATION, (81.92, 0.0)), Answer(1, Task.FORCE, (-0.001,)),
                Answer(1, Task.FORCE, (math.nan,)), Answer(1, Task.VIBRATION, (3e5,))):
        with pytest.raises(ProtocolError, match="outside"):
            host.command(bad)
    with pytest.raises(ProtocolError, match="carries 2 value"):
        host.command(Answer(1, Task.LOCALISATION, (1.0,)))
    with pytest.raises(ProtocolError, match="does not fit 4"):
        host.command(Answer(1, 16, (0,)))
    with pytest.raises(ProtocolError, match="protocols.Answer"):
        host.command(Command(1, CommandCode.ANSWER, 3))


def test_status_counters_unwrap_across_modulo() -> None:
    """Counters sent modulo 2**32 (2**24 classic) come back whole when statuses are regular."""
    for make in (lambda: (SerialEncoder(), SerialDecoder()),
                 lambda: (CanEncoder(), CanDecoder())):
        enc, dec = make()
        seen = []
        for k in range(6):
            v = (1 << 32) - 100 + 60 * k
            status = Status(k, v, v, 0, 0, (1 << 24) - 2 + k, 0, True)
            seen += dec.feed(enc.status(status)).records
        assert [s.events_generated for s in seen] == [(1 << 32) - 100 + 60 * k
                                                      for k in range(6)]
        assert [s.late_ticks for s in seen] == [(1 << 24) - 2 + k for k in range(6)]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_bad_events_raise_protocol_error(layout: str) -> None:
    def enc() -> SerialEncoder | CanEncoder:
        return SerialEncoder() if layout == "serial" else CanEncoder(fd=layout == "canfd")

    with pytest.raises(ProtocolError, match="address"):
        enc().events(make_events([0], [338]), 100)
    with pytest.raises(ProtocolError, match="multiples"):
        enc().events(make_events([50], [3]), 100)
    with pytest.raises(ProtocolError, match="must lie in"):
        enc().events(make_events([100], [3]), 100)
    e = enc()
    e.events(make_events([0], [1]), 1000)
    with pytest.raises(ProtocolError, match="must lie in"):
        e.events(make_events([500], [1]), 2000)
    with pytest.raises(ProtocolError, match="does not fit"):
        enc().command(Command(70000, CommandCode.START))


def test_empty_calls_emit_sync_only_when_due() -> None:
    enc = SerialEncoder(sync_us=10_000)
    assert enc.events(np.empty(0, EVENT_DTYPE), 1000) == b""
    enc.events(make_events([1000], [1]), 2000)
    assert enc.events(np.empty(0, EVENT_DTYPE), 5000) == b""
    sync = enc.events(np.empty(0, EVENT_DTYPE), 20_000)
    dec = SerialDecoder()
    dec.feed(sync)
    assert dec.counters.syncs == 1


@pytest.mark.parametrize("fd", [False, True])
def test_host_command_gaps_are_not_board_frame_loss(fd: bool) -> None:
    """On a shared CAN bus a decoder sees hosts' COMMAND frames too: their sequence numbers
    (two hosts, each its own counter) jump, and that is counted apart from the board's."""
    board = CanEncoder(board_id=3, fd=fd)
    hosts = [CanEncoder(board_id=3, fd=fd), CanEncoder(board_id=3, fd=fd)]
    frames = board.events(make_events([0, 100], [1, 2]), 1000)
    for i in range(6):  # host 0 sends three, then host 1 three, interleaved with board frames
        frames += hosts[i // 3].command(Command(i, CommandCode.PING))
        frames += board.ack(Ack(i, CommandCode.PING, True))
    dec = CanDecoder(board_id=3, fd=fd)
    res = dec.feed(frames)
    assert len(res.events) == 2 and len([r for r in res.records if isinstance(r, Command)]) == 6
    assert dec.counters.frames_lost == 0 and dec.counters.seq_gaps == 0
    assert dec.counters.command_seq_gaps == 1  # host 1 restarts at 0 after host 0's 2
    assert dec.counters.commands_lost == (256 if fd else 16) - 3
