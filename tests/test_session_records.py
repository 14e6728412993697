"""The session records (SPEC.md §3.7, §5.8) on every layout, the board's SESSION on request,
and the commands around the wire: ``skinhil stimuli`` and ``skinhil pty``."""

from __future__ import annotations

import dataclasses
import json
import os
import select
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from harness.peers import PtyPeer
from harness.serve import RUN_DIR, run_serve, serve_env
from protocol_examples import RUN_END, SESSION, SESSION_RECORDS, framed

import protocols
from firmware_sim.board import Board, BoardConfig
from protocols import CanDecoder, CanEncoder, SerialDecoder, SerialEncoder, StimulusEntry
from protocols.errors import ProtocolError
from protocols.session_layout import session_payload, stimulus_payload
from skinhil.model.stimulus_table import catalog, stimulus_table
from skinhil.transports import SerialTransport

LONG = StimulusEntry(100, "ü" * 32)
"""A row whose name is 64 bytes of UTF-8 (the most): 10 classic chunks, 2 FD chunks."""


@pytest.mark.parametrize("fd", [False, True])
def test_can_session_records_survive_a_lost_chunk(fd: bool) -> None:
    """A record with a chunk missing gives nothing (never a wrong record); the records after
    it decode whole, and a repeated run of chunks does not make a second record."""
    enc = CanEncoder(board_id=2, fd=fd)
    records = [*SESSION_RECORDS, LONG, RUN_END]
    frames = [enc.session_record(r) for r in records]
    assert len(frames[3]) == (2 if fd else 10)
    whole = [f for group in frames for f in group]
    assert CanDecoder(board_id=2, fd=fd).feed(whole).records == records
    for victim in (0, 3):  # the SESSION's, then the long name's, second chunk is lost
        if len(frames[victim]) < 2:
            continue
        dec = CanDecoder(board_id=2, fd=fd)
        damaged = [f for i, group in enumerate(frames) for j, f in enumerate(group)
                   if (i, j) != (victim, 1)]
        got = dec.feed(damaged).records
        assert got == [r for i, r in enumerate(records) if i != victim]
        assert dec.counters.seq_gaps == 1 and dec.counters.malformed == 0
    dec = CanDecoder(board_id=2, fd=fd)  # a late repeat of a record's chunks: duplicates
    assert dec.feed(whole + frames[4]).records == records


def test_serial_session_record_fields_are_checked() -> None:
    """Invalid fields of §3.7 make a session packet malformed (good CRC): a NaN SNR, a step
    of 0, a name length that is not the packet's, a RUN_END reason above 3."""
    good = SerialEncoder().session_record(SESSION)
    assert SerialDecoder().feed(good).records == [SESSION]
    with pytest.raises(ProtocolError):
        SerialEncoder().session_record(StimulusEntry(1, "x" * 65))  # 65 bytes: too long
    body = bytes([7 << 5, 0]) + session_payload(SESSION)
    nan = body[:23] + bytes.fromhex("0000c07f") + body[27:]  # binary32 NaN at P[21..24]
    step0 = body[:13] + b"\x00\x00" + body[15:]
    name = bytes([7 << 5 | 1, 0]) + stimulus_payload(StimulusEntry(3, "abc"))
    bad = [framed(nan), framed(step0), framed(name[:6] + b"\x04" + name[7:]),
           framed(bytes([7 << 5 | 2, 0]) + bytes(6) + b"\x04")]
    for packet in bad:
        dec = SerialDecoder()
        assert dec.feed(packet).records == [] and dec.counters.malformed == 1
    assert SerialDecoder().feed(framed(name)).records == [StimulusEntry(3, "abc")]


def test_board_sends_its_session_at_start_on_request_and_its_end(pty_pair) -> None:
    """The first records are the SESSION (START) and its table; QUERY_SESSION after SET_SNR
    is answered by an ACK, then a SESSION (REQUEST) with the new SNR and the table; the
    last record is RUN_END (DURATION), after the final STATUS."""
    config = BoardConfig(snr_db=10.0, seed=1, rest_s=0.05, response_window_s=0.3)
    peer = PtyPeer(pty_pair.master)
    codes = protocols.CommandCode
    tokens: list[int] = []

    def host() -> None:
        peer.wait_for(lambda p: p.of(protocols.Status), 30)
        tokens.append(peer.command(codes.SET_SNR, 20.0))
        tokens.append(peer.command(codes.QUERY_SESSION))

    try:
        board = Board(config, lambda: SerialTransport(pty_pair.path, baud=921600))
        threading.Thread(target=host, daemon=True).start()
        board.run(0.6)
        assert peer.wait_for(lambda p: p.of(protocols.RunEnd), 10)
    finally:
        peer.close()
    recs = peer.records
    table = stimulus_table(catalog())
    first = recs[0]
    assert isinstance(first, protocols.Session) and recs[1:1 + len(table)] == table
    assert (first.reason, first.snr_db, first.response_window_us, first.n_channels,
            first.rows, first.cols, first.tick_us, first.step_us) == (
        protocols.SessionReason.START, 10.0, 300_000, 338, 6, 6, 1000, 100)
    assert first.n_stimuli == 14 and first.table_digest == protocols.table_digest(table)
    acks = {a.token: a for a in peer.of(protocols.Ack)}
    assert all(acks[t].ok for t in tokens)
    asked = [r for r in recs if isinstance(r, protocols.Session)][1:]
    assert len(asked) == 1 and asked[0].reason == protocols.SessionReason.REQUEST
    assert asked[0].snr_db == 20.0
    at = recs.index(asked[0])
    assert recs.index(acks[tokens[1]]) < at and recs[at + 1:at + 1 + len(table)] == table
    final = peer.of(protocols.Status)[-1]
    assert recs[-2:] == [final, protocols.RunEnd(final.t_us, protocols.RunEndReason.DURATION)]


def test_stimuli_command_lists_the_table_and_a_schedule(tmp_path: Path, capsys) -> None:
    from skinhil.cli import main

    assert main(["stimuli", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [r["id"] for r in doc["stimuli"]] == [*range(9), *range(10, 15)]
    assert doc["stimuli"][10 - 1]["name"] == "A" and doc["schedule"] == []
    assert doc["table_digest"] == protocols.table_digest(stimulus_table(catalog()))
    sched = tmp_path / "s.toml"
    sched.write_text('[[stimulus]]\nname = "poke"\nforces = { 15 = [0.0, 0.0, -0.4] }\n\n'
                     '[[event]]\nstart_s = 0.5\nstimulus = "poke"\n\n'
                     '[[event]]\nstart_s = 1.0\nstimulus = "B"\n', encoding="utf-8")
    assert main(["stimuli", "--schedule", str(sched)]) == 0
    text = capsys.readouterr().out
    assert "  100  poke" in text and "id    11  B" in text and "15 stimuli" in text
    assert main(["stimuli", "--schedule", str(tmp_path / "none.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("skinhil: error: ")


def test_pty_command_links_two_devices_both_ways() -> None:
    proc = subprocess.Popen([sys.executable, "-m", "skinhil", "pty"], cwd=RUN_DIR,
                            env=serve_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    fds: list[int] = []
    try:
        assert proc.stdout is not None
        a, b = proc.stdout.readline().strip(), proc.stdout.readline().strip()
        assert a.startswith("/dev/pts/") and b.startswith("/dev/pts/") and a != b
        fds = [os.open(p, os.O_RDWR | os.O_NOCTTY) for p in (a, b)]
        for src, dst in ((0, 1), (1, 0), (0, 1)):
            data = bytes(range(256)) * 40  # every byte value, 10 KiB, raw (no translation)
            os.write(fds[src], data)
            got = b""
            end = time.monotonic() + 10
            while len(got) < len(data) and time.monotonic() < end:
                if select.select([fds[dst]], [], [], 0.2)[0]:
                    got += os.read(fds[dst], 65536)
            assert got == data
        proc.send_signal(signal.SIGINT)
        assert proc.wait(10) == 130
        assert proc.stderr is not None and "Traceback" not in proc.stderr.read()
    finally:
        for fd in fds:
            os.close(fd)
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_serve_banner_states_its_snr() -> None:
    """serve's default is the paper's 10 dB, as train and demo; its banner says so."""
    res = run_serve("--port", "loop://", "--duration", "0.05")
    assert res.returncode == 0, res.stderr
    banner = res.stderr.splitlines()[0]
    assert "SNR 10 dB neuron noise" in banner, banner


def test_an_internal_error_ends_the_run_with_run_end_error(pty_pair) -> None:
    """A board whose tick fails still closes the account and says ERROR on the wire (a
    receiver does not take the silence for a dead link), then raises the error."""

    class FailingBoard(Board):
        def tick(self) -> None:
            if self.clock.index == 200:
                raise RuntimeError("model blew up")
            super().tick()

    peer = PtyPeer(pty_pair.master)
    try:
        board = FailingBoard(BoardConfig(seed=2, rest_s=0.05),
                             lambda: SerialTransport(pty_pair.path, baud=921600))
        with pytest.raises(RuntimeError, match="model blew up"):
            board.run(1.0)
        assert peer.wait_for(lambda p: p.of(protocols.RunEnd), 10)
    finally:
        peer.close()
    final = peer.of(protocols.Status)[-1]
    assert peer.records[-2:] == [final, protocols.RunEnd(final.t_us,
                                                        protocols.RunEndReason.ERROR)]
    assert final.t_us == 200_000 and final.events_queued == 0


def test_a_session_of_an_earlier_revision_announces_no_task_and_no_blind_link() -> None:
    """Bytes 32..33 and flag bit 1, reserved in the earlier revision (sent as 0), decode as
    ``tasks`` 0 (not announced) and not blind; the example's 0x000F and blind flag round-trip
    through every layout (SPEC.md §3.7)."""
    old = dataclasses.replace(SESSION, tasks=0, blind=False)
    payload = session_payload(SESSION)
    assert payload[27] == 0x03 and payload[32:35] == bytes([0x0F, 0, 0])
    assert session_payload(old)[27] == 0x01 and session_payload(old)[32:35] == bytes(3)
    assert SerialDecoder().feed(SerialEncoder().session_record(old)).records == [old]
    for fd in (False, True):
        frames = CanEncoder(board_id=1, fd=fd).session_record(SESSION)
        assert CanDecoder(board_id=1, fd=fd).feed(frames).records == [SESSION]
