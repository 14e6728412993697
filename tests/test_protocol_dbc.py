"""cantools, with its default settings, decodes every frame the board sends from the DBC
alone: boards 0 and 9, classic CAN and CAN FD, encoder output and a live board's bus.

The events a DBC user gets (the ``Ev<i>`` slots that are not ``NONE``, timed from SYNC's
base, the frame's offset and the deltas) must be exactly the protocol decoder's: no phantom
event from an empty slot, none missing.
"""

from __future__ import annotations

import random
import threading
from typing import Any

import cantools
import numpy as np
import pytest
from protocol_examples import distinct_events

import protocols
from firmware_sim.board import Board, BoardConfig
from protocols import DBC_FD_PATH, DBC_PATH, CanEncoder
from protocols.dbc import dbc_text
from protocols.status_layout import STATUS_WORDS
from skinhil.transports import CanTransport

NAMES = {1: "SKIN_COMMAND", 2: "SKIN_ACK", 3: "SKIN_SYNC", 4: "SKIN_STATUS", 5: "SKIN_MARKER",
         6: "SKIN_EVENTS"}
"""The frames of the stream proper (and a host's); SKIN_WIDE_EVENTS is a larger skin's."""
SESSION_NAMES = {8: "SKIN_SESSION", 9: "SKIN_STIMULUS", 10: "SKIN_RUN_END", 11: "SKIN_SUITE"}
"""The session records a running board sends at its start and end (SPEC.md §5.8); a board
playing a suite case sends SKIN_TASK records too."""


def _camel(name: str) -> str:
    return "".join(p.capitalize() for p in name.split("_"))


class DbcReader:
    """What a user writes with cantools and the DBC: decode frames, time events by SYNC."""

    def __init__(self, board_id: int, fd: bool) -> None:
        self.db = cantools.database.load_string(dbc_text(board_id, fd), database_format="dbc")
        self.fd = fd
        self.base_us: int | None = None
        self.step_us = 0
        self.events: list[tuple[int, int]] = []
        self.names: set[str] = set()
        self.statuses: list[dict[str, Any]] = []
        self.markers: list[dict[str, Any]] = []
        self.sessions: list[dict[str, Any]] = []
        self.stimuli: list[dict[str, Any]] = []
        self.run_ends: list[dict[str, Any]] = []
        self.suites: list[dict[str, Any]] = []
        self._mux: dict[str, Any] = {}
        self._session: dict[str, Any] = {}

    def feed(self, frame: Any) -> None:
        msg = self.db.get_message_by_frame_id(frame.arbitration_id)
        d = msg.decode(frame.data)  # cantools' defaults: no allow_truncated, choices named
        self.names.add(msg.name)
        if msg.name == "SKIN_SYNC":
            self.step_us = int(d["StepUs"])
            self.base_us = int(d["BaseSteps"]) * self.step_us
        elif msg.name in ("SKIN_EVENTS", "SKIN_WIDE_EVENTS"):
            assert self.base_us is not None
            ev = "Ev" if msg.name == "SKIN_EVENTS" else "WEv"
            slots = sum(1 for s in msg.signals if s.name.startswith(ev) and "Addr" in s.name)
            addrs = [d[f"{ev}{i}Addr"] for i in range(slots)]
            n = sum(isinstance(a, int) for a in addrs)
            assert all(isinstance(a, int) for a in addrs[:n])  # events first, then NONE
            assert all(a == "NONE" for a in addrs[n:]) and n >= 1
            if self.fd:
                assert d["Count"] == n
            t = self.base_us + int(d["Offset"]) * self.step_us
            for i in range(n):
                t += int(d[f"{ev}{i}Delta"]) * self.step_us
                self.events.append((t, int(addrs[i])))
        elif msg.name == "SKIN_STATUS":
            if self.fd:
                self.statuses.append(d)
            else:
                self._mux = {} if d["Mux"] == 0 else self._mux
                self._mux.update(d)
                if d["Mux"] == 7:
                    self.statuses.append(dict(self._mux))
        elif msg.name == "SKIN_MARKER":
            self.markers.append(d)
        elif msg.name == "SKIN_SESSION":  # classic: chunks 0..5, FD: one frame
            self._session = {} if d["Chunk"] == 0 else self._session
            self._session.update(d)
            if "TableDigest" in d:
                self.sessions.append(dict(self._session))
        elif msg.name == "SKIN_STIMULUS" and d["Chunk"] == 0:
            self.stimuli.append(d)
        elif msg.name == "SKIN_RUN_END":
            self.run_ends.append(d)
        elif msg.name == "SKIN_SUITE":
            self.suites.append(d)


def _protocol_events(frames: list[Any], board_id: int, fd: bool) -> tuple[list[Any], Any]:
    dec = protocols.CanDecoder(board_id=board_id, fd=fd)
    res = dec.feed(frames)
    return list(zip(res.events["t"].tolist(), res.events["addr"].tolist(), strict=True)), res


def _check_status(got: dict[str, Any], want: protocols.Status) -> None:
    assert got["TimeUs"] == want.t_us and got["Running"] == int(want.running)
    for name in STATUS_WORDS:
        if name != "link_events":
            assert got[_camel(name)] == getattr(want, name), name


def test_committed_dbcs_are_the_generator_output() -> None:
    assert DBC_PATH.read_text(encoding="ascii") == dbc_text(0, fd=False)
    assert DBC_FD_PATH.read_text(encoding="ascii") == dbc_text(0, fd=True)


@pytest.mark.parametrize("fd", [False, True])
@pytest.mark.parametrize("board_id", [0, 9])
def test_cantools_decodes_encoder_frames(board_id: int, fd: bool) -> None:
    rng = random.Random(board_id * 2 + fd)
    enc = CanEncoder(board_id=board_id, fd=fd)
    frames: list[Any] = []
    sent: list[protocols.Status] = []
    t_end = 0
    for call in range(300):  # sparse and crowded calls: partial and full frames, SYNCs
        n = rng.choice([0, 1, 3, 7, 60])
        t0, t_end = t_end, t_end + 1000
        t = sorted(rng.randrange(t0, t_end, 100) for _ in range(n))
        frames += enc.events(distinct_events(t, [rng.randrange(338) for _ in t]), t_end)
        if call % 50 == 0:
            sent.append(protocols.Status(t_end, 7 * call, 5 * call, 2 * call, 0, call, 0,
                                         call % 100 == 0, call, call, 0, 0, call // 2, 1))
            frames += enc.status(sent[-1])
            frames += enc.marker(protocols.Marker(t_end, call % 9, protocols.MarkerPhase.END))
    frames += enc.ack(protocols.Ack(5, protocols.CommandCode.PING, True))
    host = CanEncoder(board_id=board_id, fd=fd).command(
        protocols.Command(9, protocols.CommandCode.SET_STIMULUS, 3))
    reader = DbcReader(board_id, fd)
    for f in frames + host:
        reader.feed(f)
    assert reader.names == set(NAMES.values())
    want, _ = _protocol_events(frames, board_id, fd)
    assert len(want) > 1000 and reader.events == want
    assert len(reader.statuses) == len(sent)
    for got, status in zip(reader.statuses, sent, strict=True):
        _check_status(got, status)
    assert [m["StimulusId"] for m in reader.markers] == [c % 9 for c in range(0, 300, 50)]


@pytest.mark.parametrize("fd", [False, True])
def test_cantools_decodes_wide_frames(fd: bool) -> None:
    """A skin of more than 338 channels sends SKIN_WIDE_EVENTS: the same DBC decodes them."""
    rng = random.Random(fd)
    enc = CanEncoder(board_id=9, fd=fd, n_channels=15_730)
    frames: list[Any] = []
    for call in range(100):
        t = sorted(rng.randrange(1000 * call, 1000 * call + 1000, 100)
                   for _ in range(rng.choice([1, 5, 30])))
        frames += enc.events(distinct_events(t, [rng.randrange(15_730) for _ in t]),
                             1000 * call + 1000)
    reader = DbcReader(9, fd)
    for f in frames:
        reader.feed(f)
    assert reader.names == {"SKIN_SYNC", "SKIN_WIDE_EVENTS"}
    want, _ = _protocol_events(frames, 9, fd)
    assert len(want) > 500 and reader.events == want


@pytest.mark.parametrize("fd", [False, True])
@pytest.mark.parametrize("board_id", [0, 9])
def test_cantools_decodes_a_live_board(board_id: int, fd: bool) -> None:
    """Every frame on the bus of a running board (and a host's command) decodes with the
    DBC of its id; the DBC user's events are the protocol decoder's, frame for frame."""
    chan = f"dbc-{random.getrandbits(32)}"
    sniffer = CanTransport(chan, "virtual", fd=fd)
    host = CanTransport(chan, "virtual", fd=fd)
    config = BoardConfig(board_id=board_id, snr_db=0.0, seed=board_id, rest_s=0.05)
    board = Board(config, lambda: CanTransport(chan, "virtual", fd=fd, bitrate=500_000))
    stop = threading.Event()
    query = CanEncoder(board_id=board_id, fd=fd).command(
        protocols.Command(1, protocols.CommandCode.QUERY_STATUS))
    threading.Timer(0.3, lambda: host.send(query, timeout=1.0)).start()
    try:
        board.run(0.8, stop)
        frames: list[Any] = []
        while chunk := sniffer.recv(timeout=0.3):
            frames += chunk
    finally:
        sniffer.shutdown()
        host.shutdown()
    reader = DbcReader(board_id, fd)
    for f in frames:
        reader.feed(f)
    assert reader.names == set((NAMES | SESSION_NAMES).values())
    board_frames = [f for f in frames if f.arbitration_id >> 4 != 1]
    want, res = _protocol_events(board_frames, board_id, fd)
    assert len(want) > 100 and reader.events == want
    final = [r for r in res.records if isinstance(r, protocols.Status)][-1]
    _check_status(reader.statuses[-1], final)
    assert final.events_sent == len(want)
    # the session records: the DBC user reads what the protocol decoder does
    session = next(r for r in res.records if isinstance(r, protocols.Session))
    got = reader.sessions[0]
    assert (got["NChannels"], got["StepUs"], got["BoardId"], got["TickUs"], got["SnrDb"],
            got["ResponseWindowUs"], got["NStimuli"], got["TableDigest"], got["Reason"]) == (
        338, 100, board_id, 1000, 0.0, 500_000, session.n_stimuli, session.table_digest, "START")
    stimuli = [r for r in res.records if isinstance(r, protocols.StimulusEntry)]
    assert [d["StimulusId"] for d in reader.stimuli] == [e.stimulus_id for e in stimuli]
    assert len(stimuli) == session.n_stimuli == 14
    assert protocols.table_digest(stimuli) == session.table_digest
    assert board_frames[-1].arbitration_id >> 4 == 10  # RUN_END is the last frame
    assert [d["Reason"] for d in reader.run_ends] == ["DURATION"]
    # no suite: the SUITE record's lengths are 0 and no TASK record follows
    assert [(d["NameLength"], d["CaseLength"], d["NTasks"]) for d in reader.suites] == [(0, 0, 0)]
    assert isinstance(res.records[-1], protocols.RunEnd)
    # one length per frame type, the DBC's
    assert {(f.arbitration_id, len(f.data)) for f in frames} == {
        (m.frame_id, m.length) for m in reader.db.messages
        if m.name in (NAMES | SESSION_NAMES).values()}
    assert np.all(np.diff([t for t, _ in want]) >= 0)


def test_dbc_command_writes_the_generator_output(tmp_path, capsys) -> None:
    from skinhil.cli import main

    out = tmp_path / "board9_fd.dbc"
    assert main(["dbc", "--board-id", "9", "--fd", "--out", str(out)]) == 0
    assert out.read_text(encoding="ascii") == dbc_text(9, fd=True)
    assert main(["dbc", "--board-id", "16"]) == 2
    assert "board id from 0 to 15" in capsys.readouterr().err


@pytest.mark.parametrize("fd", [False, True])
def test_cantools_encodes_and_decodes_decisions(fd: bool) -> None:
    """A DUT written with cantools alone sends the DECISION the codec sends, and reads one:
    the COMMAND frame is multiplexed by its opcode (Arg, or the decision's two fields)."""
    db = cantools.database.load_string(dbc_text(9, fd), database_format="dbc")
    msg = db.get_message_by_name("SKIN_COMMAND")
    for seq, (sid, conf, raw) in enumerate([(3, 0.5, 127), (70_000, None, 255), (0, 1.0, 254)]):
        (frame,) = CanEncoder(board_id=9, fd=fd).command(protocols.Decision(seq, sid, conf))
        assert frame.arbitration_id == msg.frame_id
        fields = {"Seq": 0, "Opcode": "DECISION", "Token": seq, "DecisionStimulusId": sid,
                  "DecisionConfidence": raw}
        assert msg.encode(fields) == frame.data
        want = dict(fields, DecisionConfidence="NONE" if conf is None else raw)
        assert msg.decode(frame.data) == want
        (got,) = protocols.CanDecoder(board_id=9, fd=fd).feed([frame]).records
        assert got == protocols.Decision(seq, sid, conf)
    (frame,) = CanEncoder(board_id=9, fd=fd).command(
        protocols.Command(4, protocols.CommandCode.SET_STIMULUS, 11))
    assert msg.decode(frame.data) == {"Seq": 0, "Opcode": "SET_STIMULUS", "Token": 4, "Arg": 11}


@pytest.mark.parametrize("fd", [False, True])
def test_cantools_encodes_and_decodes_answers(fd: bool) -> None:
    """An ANSWER's fields, multiplexed by AnswerTask inside opcode ANSWER, come out of
    cantools in physical units, and cantools encodes the codec's frame from them."""
    db = cantools.database.load_string(dbc_text(9, fd), database_format="dbc")
    msg = db.get_message_by_name("SKIN_COMMAND")
    task = protocols.Task
    cases = [(protocols.Answer(1, task.LOCALISATION, (1.25, -2.5)),
              {"AnswerXmm": 1.25, "AnswerYmm": -2.5}),
             (protocols.Answer(2, task.FORCE, (0.3,)), {"AnswerForceN": 0.3}),
             (protocols.Answer(3, task.SLIP, ()), {}),
             (protocols.Answer(4, task.VIBRATION, (100.0,)), {"AnswerFrequencyHz": 100.0}),
             (protocols.Answer(5, task.CLASSIFICATION, (7,)), {"AnswerStimulusId": 7})]
    for answer, values in cases:
        (frame,) = CanEncoder(board_id=9, fd=fd).command(answer)
        fields = {"Seq": 0, "Opcode": "ANSWER", "Token": answer.token,
                  "AnswerTask": answer.task.name, **values}
        got = msg.decode(frame.data)
        assert got.keys() == fields.keys()
        assert all(got[k] == pytest.approx(v) if isinstance(v, float) else got[k] == v
                   for k, v in fields.items()), got
        assert msg.encode(fields) == frame.data
