"""``serve --record`` and ``serve --replay``: what the board put on the link is recorded
exactly, and replayed onto a second link (a second pty, UDP port or vcan bus) byte for byte,
datagram for datagram, frame for frame; host commands during a replay get a NACK
(REPLAYING) without breaking the stream's sequence numbers; the CAN log reads back with
``can.LogReader`` and decodes with cantools; bad recordings give one error line."""

from __future__ import annotations

import io
import json
import subprocess
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import PtyPair, PtyReader
from harness.peers import CanPeer, UdpPeer
from harness.serve import RUN_DIR, ServeProcess, run_serve, serve_argv, serve_env

import protocols
from protocols.capture import (
    CaptureHeader,
    CaptureWriter,
    read_header,
    read_units,
)
from protocols.events import make_events
from skinhil.errors import ProtocolError
from skinhil.transports.udp import MAX_DATAGRAM_BYTES, split_packets

SERVE_ARGS = ("--duration", "1.5", "--rest", "0.05", "--seed", "3", "--json")
"""A short board run with several stimuli (markers) and a steady event stream."""


def capture_units(path: Path) -> tuple[CaptureHeader, list[bytes]]:
    with open(path, "rb") as f:
        header = read_header(f)
        return header, [u.payload for u in read_units(f, header.format_version)]


def replay_json(proc: subprocess.CompletedProcess[str]) -> dict[str, Any]:
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stdout.splitlines() if '"replay"' in ln]
    return json.loads(lines[-1])


def decoded(data: bytes) -> protocols.DecodeResult:
    return protocols.SerialDecoder().feed(data)


# -- the capture format (protocols/capture.py) ------------------------------------------
def _capture_bytes(units: list[bytes], wire: int = 3, link: str = "serial",
                   spacing_ns: int = 1) -> bytes:
    f = io.BytesIO()
    w = CaptureWriter(f, CaptureHeader(wire, link, 100, 1_000))
    for k, u in enumerate(units):
        w.write(2_000 + k * spacing_ns, 10 * k, u)
    w.close(9_999)
    return f.getvalue()


def test_capture_round_trip_and_every_truncation_is_refused() -> None:
    units = [b"\x01\x02\x00", b"abc" * 50, b"\x00"]
    raw = _capture_bytes(units)
    f = io.BytesIO(raw)
    header = read_header(f)
    got = list(read_units(f))
    assert header == CaptureHeader(3, "serial", 100, 1_000)
    assert [u.payload for u in got] == units
    assert [(u.host_ns, u.board_us) for u in got] == [(2_000, 0), (2_001, 10), (2_002, 20)]
    for cut in range(len(raw)):  # every prefix: refused, never read as whole
        with pytest.raises(ProtocolError):
            f = io.BytesIO(raw[:cut])
            read_header(f)
            list(read_units(f))
    with pytest.raises(ProtocolError, match="does not close"):
        f = io.BytesIO(raw + b"\x00")
        read_header(f)
        list(read_units(f))
    with pytest.raises(ProtocolError, match="wire version 5"):
        read_header(io.BytesIO(_capture_bytes(units, wire=5)))


def test_every_bit_flip_in_a_capture_is_refused_as_damaged() -> None:
    """Format version 2 carries a CRC-32 per record: a flipped bit anywhere after the header
    (a payload, a record header, the end record) is refused, never replayed."""
    raw = _capture_bytes([b"\x01\x02\x00", b"abc" * 20])
    header = read_header(io.BytesIO(raw))
    assert header.format_version == 2 and header.checked
    for pos in range(32, len(raw)):
        for bit in (0, 3, 7):
            damaged = bytearray(raw)
            damaged[pos] ^= 1 << bit
            f = io.BytesIO(bytes(damaged))
            read_header(f)
            with pytest.raises(ProtocolError):
                list(read_units(f, header.format_version))


def test_a_version_1_capture_is_read_without_its_check() -> None:
    """Captures of format version 1 (no CRC-32) are still read, and say they are unchecked."""
    import struct

    units = [b"\x01\x02\x00", b"xyz"]
    raw = struct.pack("<8sHBBIqQ", b"SKHLCAP\n", 1, 3, 1, 100, 1_000, 0)
    for k, u in enumerate(units):
        raw += struct.pack("<qqI", 2_000 + k, 10 * k, len(u)) + u
    raw += struct.pack("<qqI", 9_999, len(units), 0xFFFFFFFF)
    f = io.BytesIO(raw)
    header = read_header(f)
    assert header.format_version == 1 and not header.checked
    assert [u.payload for u in read_units(f, header.format_version)] == units


# -- serial: a pty -------------------------------------------------------------------------
def test_record_on_a_pty_then_replay_onto_a_second_pty_byte_for_byte(tmp_path) -> None:
    rec = tmp_path / "session.skcap"
    first, second = PtyPair(), PtyPair()
    reader = PtyReader(first.master)
    try:
        serve = run_serve("--port", first.path, "--record", str(rec), *SERVE_ARGS,
                          timeout_s=120)
        assert serve.returncode == 0, serve.stderr
        time.sleep(0.3)
        sent = reader.take()
        reader.stop()
        header, units = capture_units(rec)
        assert header.link == "serial" and header.wire_version == 3 and header.step_us == 100
        recorded = b"".join(units)
        assert recorded == sent  # exactly what the board put on the link
        result = decoded(recorded)
        markers = [r for r in result.records if isinstance(r, protocols.Marker)]
        assert len(result.events) > 100 and len(markers) >= 4
        assert not list(tmp_path.glob(".*partial*"))  # the temporary file was renamed

        reader = PtyReader(second.master)
        replay = run_serve("--port", second.path, "--replay", str(rec), "--json",
                           timeout_s=60)
        info = replay_json(replay)
        time.sleep(0.3)
        assert reader.take() == recorded  # byte for byte
        assert info["complete"] and info["units"] == len(units)
        assert info["wire_units"] == len(recorded)
        assert info["markers"] == len(markers) and info["events"] == len(result.events)
        assert info["commands"] == 0
    finally:
        reader.stop()
        first.close()
        second.close()


def _replay_with_pings(rec: Path, tokens: tuple[int, ...], started: Any
                       ) -> tuple[subprocess.Popen[str], bytearray, str, str]:
    """``serve --replay rec`` onto a pty; once ``started(bytes so far)``, a PING per token
    (50 ms apart); the process, every byte it sent, its stdout and stderr."""
    pair = PtyPair()
    reader = PtyReader(pair.master)
    host = protocols.SerialEncoder()
    try:
        proc = subprocess.Popen(serve_argv("--port", pair.path, "--replay", str(rec),
                                           "--json"), cwd=RUN_DIR, env=serve_env(),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        got = bytearray()
        deadline = time.monotonic() + 60
        while not started(got) and time.monotonic() < deadline:
            got += reader.take()
            time.sleep(0.01)
        for token in tokens:
            pair.write(host.command(protocols.Command(token=token,
                                                      opcode=protocols.CommandCode.PING)))
            time.sleep(0.05)
        out, err = proc.communicate(timeout=60)
        time.sleep(0.2)
        got += reader.take()
    finally:
        reader.stop()
        pair.close()
    return proc, got, out, err


def test_commands_during_a_replay_are_nacked_and_the_stream_stays_whole(tmp_path) -> None:
    """A host sends commands while a recording plays: each gets a NACK with reason
    REPLAYING, and the stream around the answers decodes with no sequence gap and every
    recorded event and marker (the packets after each answer renumbered)."""
    enc = protocols.SerialEncoder()
    packets = []
    for k in range(60):  # 60 packets: events, markers, statuses, 10 ms apart
        t0 = k * 10_000
        ev = make_events(np.array([t0, t0 + 100]), np.array([k % 338, 7]))
        packets.append(enc.events(ev, t0 + 10_000))
        if k % 10 == 0:
            packets.append(enc.marker(protocols.Marker(t_us=t0, stimulus_id=k // 10,
                                                       phase=protocols.MarkerPhase.ONSET)))
    units = [p for p in packets if p]
    rec = tmp_path / "made.skcap"
    rec.write_bytes(_capture_bytes(units, spacing_ns=10_000_000))
    recorded = decoded(b"".join(units))

    proc, got, out, err = _replay_with_pings(rec, (11, 12, 13), lambda got: bool(got))
    assert proc.returncode == 0, err
    res = protocols.SerialDecoder()
    result = res.feed(bytes(got))
    acks = [r for r in result.records if isinstance(r, protocols.Ack)]
    assert [(a.token, a.ok, a.reason) for a in acks] == [
        (t, False, protocols.NackReason.REPLAYING) for t in (11, 12, 13)]
    c = res.counters
    assert c.seq_gaps == 0 and c.duplicates == 0 and c.crc_errors == 0 and c.malformed == 0
    assert np.array_equal(result.events, recorded.events)
    assert [r for r in result.records if isinstance(r, protocols.Marker)] == \
        [r for r in recorded.records if isinstance(r, protocols.Marker)]
    assert '"commands": 3' in out


def test_a_crafted_capture_with_an_overlong_run_replays_and_answers_a_ping(tmp_path) -> None:
    """A capture holding a 2,295-byte COBS run (longer than any packet) between real packets:
    the run is played as recorded (it is no packet, so it is not renumbered) and a PING
    during the replay is answered. The run once overflowed the re-framing buffer of
    protocols/resequence.py (the board aborted with ``malloc(): invalid size``)."""
    enc = protocols.SerialEncoder()
    crafted = (bytes([255] + [7] * 254) * 10)[:2_295] + b"\x00"
    units = [enc.events(make_events(np.array([k * 10_000]), np.array([k])), (k + 1) * 10_000)
             for k in range(30)]
    units[3:3] = [crafted]
    rec = tmp_path / "crafted.skcap"
    rec.write_bytes(_capture_bytes(units, spacing_ns=20_000_000))
    proc, got, _, err = _replay_with_pings(rec, (77,), lambda got: crafted in got)
    assert proc.returncode == 0, err
    assert crafted in got
    acks = [r for r in protocols.SerialDecoder().feed(bytes(got)).records
            if isinstance(r, protocols.Ack)]
    assert [(a.token, a.reason) for a in acks] == [(77, protocols.NackReason.REPLAYING)]


def test_decisions_during_a_replay_are_scored_against_the_recorded_markers(tmp_path) -> None:
    """A decoder under test answers a replayed recording: its DECISIONs are stamped with the
    board time played so far and scored against the MARKERs played (right, duplicate and
    the unanswered onsets as misses, in the --score file); other commands are NACKed."""
    enc = protocols.SerialEncoder()
    units = []
    for k in range(24):  # 1.2 s: a packet every 50 ms, an onset every 300 ms (ids 0..3)
        t0 = k * 50_000
        if k % 6 == 0:
            units.append(enc.marker(protocols.Marker(t_us=t0, stimulus_id=k // 6,
                                                     phase=protocols.MarkerPhase.ONSET)))
        units.append(enc.events(make_events(np.array([t0 + 100]), np.array([k])), t0 + 50_000))
    rec = tmp_path / "answered.skcap"
    rec.write_bytes(_capture_bytes([u for u in units if u], spacing_ns=25_000_000))
    score = tmp_path / "score.json"
    pair = PtyPair()
    reader = PtyReader(pair.master)
    host = protocols.SerialEncoder()
    stream = protocols.SerialDecoder()
    try:
        proc = subprocess.Popen(serve_argv("--port", pair.path, "--replay", str(rec),
                                           "--response-window", "0.2", "--score", str(score),
                                           "--json"), cwd=RUN_DIR, env=serve_env(),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        seen: list[int] = []
        deadline = time.monotonic() + 60
        while 1 not in seen and time.monotonic() < deadline:
            seen += [r.stimulus_id for r in stream.feed(reader.take()).records
                     if isinstance(r, protocols.Marker)]
            time.sleep(0.002)
        assert 1 in seen, "the replay never played onset 1"
        for token in (21, 22):  # right, then a duplicate of the same onset
            pair.write(host.command(protocols.Decision(token=token, stimulus_id=1)))
        pair.write(host.command(protocols.Command(token=23, opcode=protocols.CommandCode.PING)))
        out, err = proc.communicate(timeout=60)
        time.sleep(0.2)
        acks = [r for r in stream.feed(reader.take()).records if isinstance(r, protocols.Ack)]
    finally:
        reader.stop()
        pair.close()
    assert proc.returncode == 0, err
    assert [(a.token, a.ok, a.reason) for a in acks] == [
        (21, True, protocols.NackReason.NONE), (22, True, protocols.NackReason.NONE),
        (23, False, protocols.NackReason.REPLAYING)]
    board = json.loads(score.read_text())
    assert board["right"] == 1 and board["duplicates"] == 1 and board["wrong"] == 0
    assert board["misses"] >= 2  # onsets 0 and 2 had no decision in their window
    assert board["latency_ms"]["p50"] is not None and board["latency_ms"]["p50"] >= 0
    assert json.loads(out.strip().splitlines()[-1])["scoreboard"]["right"] == 1


# -- UDP ------------------------------------------------------------------------------------
def _closed(peer: Any, units: str, expected: int) -> list[Any]:
    """The raw units (``datagrams`` or ``frames``) ``peer`` received, once it holds
    ``expected`` of them or 30 s passed (its thread may still be compiling a decoder
    kernel: inside user-mode Linux that takes seconds)."""
    deadline = time.monotonic() + 30
    while len(getattr(peer, units)) < expected and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(0.3)  # and nothing more comes
    peer.close()
    return list(getattr(peer, units))


def test_record_over_udp_then_replay_datagram_for_datagram(tmp_path) -> None:
    rec = tmp_path / "udp.skcap"
    sink = UdpPeer()
    serve = run_serve("--udp", f"127.0.0.1:{sink.port}", "--record", str(rec), *SERVE_ARGS,
                      timeout_s=120)
    assert serve.returncode == 0, serve.stderr
    header, units = capture_units(rec)
    sent = _closed(sink, "datagrams",
                   sum(len(split_packets(u, MAX_DATAGRAM_BYTES)) for u in units))
    assert header.link == "udp"
    assert b"".join(units) == b"".join(sent)
    again = UdpPeer()
    info = replay_json(run_serve("--udp", f"127.0.0.1:{again.port}", "--replay", str(rec),
                                 "--json", timeout_s=60))
    assert _closed(again, "datagrams", len(sent)) == sent  # the same datagrams, in order
    assert info["complete"] and len(decoded(b"".join(sent)).events) == info["events"] > 0


# -- CAN: vcan0 -> vcan1 (inside user-mode Linux) -------------------------------------------
def _log_frames(path: Path) -> list[protocols.CanFrame]:
    import can

    return [protocols.CanFrame(m.arbitration_id, bytes(m.data), bool(m.is_fd))
            for m in can.LogReader(str(path))]


@pytest.mark.vcan
@pytest.mark.parametrize(("fd", "suffix"), [(False, ".blf"), (True, ".asc")])
def test_record_on_vcan0_then_replay_onto_vcan1_frame_for_frame(tmp_path, fd: bool,
                                                               suffix: str) -> None:
    import cantools

    rec = tmp_path / f"session{suffix}"
    extra = ["--fd"] if fd else []
    sink = CanPeer("vcan0", fd=fd)
    serve = ServeProcess("--can", "vcan0", "--record", str(rec), *extra, *SERVE_ARGS)
    assert serve.wait(180) == 0, serve.stderr
    logged = _log_frames(rec)  # python-can reads it back
    sent = _closed(sink, "frames", len(logged))
    assert logged == sent and len(sent) > 50
    db = cantools.database.load_file(str(protocols.DBC_FD_PATH if fd else protocols.DBC_PATH))
    names = {db.get_message_by_frame_id(f.arbitration_id).name for f in logged}
    assert {"SKIN_SYNC", "SKIN_STATUS", "SKIN_MARKER", "SKIN_EVENTS"} <= names
    for f in logged:  # every frame decodes with the DBC
        assert db.decode_message(f.arbitration_id, f.data)
    markers = [r for r in protocols.CanDecoder(fd=fd).feed(logged).records
               if isinstance(r, protocols.Marker)]
    assert len(markers) >= 4

    again = CanPeer("vcan1", fd=fd)
    replay = subprocess.run(serve_argv("--can", "vcan1", "--replay", str(rec), "--json",
                                       *extra), cwd=RUN_DIR, env=serve_env(), text=True,
                            capture_output=True, timeout=120)
    info = replay_json(replay)
    assert _closed(again, "frames", len(logged)) == logged  # frame for frame
    assert info["complete"] and info["markers"] == len(markers)


# -- bad recordings -------------------------------------------------------------------------
def _one_error_line(argv: list[str]) -> str:
    proc = subprocess.run(argv, cwd=RUN_DIR, env=serve_env(), text=True, capture_output=True,
                          timeout=60, stdin=subprocess.DEVNULL)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("skinhil: error: "), proc.stderr
    return lines[0]


def test_bad_recordings_give_one_error_line(tmp_path, pty_pair) -> None:
    import can

    packets = protocols.SerialEncoder().events(
        make_events(np.array([0, 100]), np.array([1, 2])), 1000)
    good = _capture_bytes([packets])
    (tmp_path / "good.skcap").write_bytes(good)
    (tmp_path / "cut.skcap").write_bytes(good[:-7])
    (tmp_path / "garbage.skcap").write_bytes(b"\x93NUMPY not a capture at all" * 10)
    (tmp_path / "v5.skcap").write_bytes(_capture_bytes([packets], wire=5))
    (tmp_path / "udp.skcap").write_bytes(_capture_bytes([packets], link="udp"))
    (tmp_path / "garbage.blf").write_bytes(b"LOGG" + bytes(range(256)) * 4)
    (tmp_path / "empty.asc").write_text("")
    frames = protocols.CanEncoder().events(
        make_events(np.array([0, 100]), np.array([1, 2])), 1000)
    assert frames[0].arbitration_id >> 4 == 3  # a SYNC first
    with can.Logger(str(tmp_path / "can.blf")) as log:
        for f in frames:
            log.on_message_received(can.Message(arbitration_id=f.arbitration_id,
                                                data=f.data, is_extended_id=False))
    sync_v5 = bytearray(protocols.CanEncoder(fd=True).events(
        make_events(np.array([0]), np.array([1])), 1000)[0].data)
    sync_v5[1] = (sync_v5[1] & 0x0F) | (5 << 4)
    with can.Logger(str(tmp_path / "v5.log")) as log:
        log.on_message_received(can.Message(arbitration_id=0x30, data=bytes(sync_v5),
                                            is_fd=True, is_extended_id=False))
    port = ["--port", pty_pair.path]
    cases = {
        "can log onto serial": (port + ["--replay", str(tmp_path / "can.blf")], "CAN log"),
        "capture onto CAN": (["--can", "vcan0", "--replay", str(tmp_path / "good.skcap")],
                             "capture"),
        "udp capture onto serial": (port + ["--replay", str(tmp_path / "udp.skcap")],
                                    "udp link"),
        "truncated": (port + ["--replay", str(tmp_path / "cut.skcap")], "truncated"),
        "garbage capture": (port + ["--replay", str(tmp_path / "garbage.skcap")],
                            "not a skinhil capture"),
        "wire version": (port + ["--replay", str(tmp_path / "v5.skcap")], "wire version 5"),
        "can wire version": (["--can", "vcan0", "--fd", "--replay", str(tmp_path / "v5.log")],
                             "wire version 5"),
        "garbage CAN log": (["--can", "vcan0", "--replay", str(tmp_path / "garbage.blf")],
                            "CAN log"),
        "empty CAN log": (["--can", "vcan0", "--replay", str(tmp_path / "empty.asc")],
                          "no frames"),
        "missing": (port + ["--replay", str(tmp_path / "nope.skcap")], "does not exist"),
        "extension": (port + ["--replay", str(tmp_path / "x.wav")], "unknown extension"),
        "record extension": (port + ["--record", str(tmp_path / "x.blf")], "CAN log"),
        "record FD to csv": (["--can", "vcan0", "--fd", "--record", str(tmp_path / "x.csv")],
                             "does not keep CAN FD"),
        "speed": (port + ["--replay", str(tmp_path / "good.skcap"), "--speed", "0"],
                  "--speed"),
        "both": (port + ["--replay", str(tmp_path / "good.skcap"), "--record",
                         str(tmp_path / "y.skcap")], "do not go together"),
    }
    for name, (args, needle) in cases.items():
        line = _one_error_line(serve_argv(*args))
        assert needle in line, (name, line)



# -- listen --record: the session recorder streams to disk ----------------------------------
def test_session_recorder_streams_events_to_a_spool_and_saves_them_whole(tmp_path) -> None:
    from skinhil.recording import SessionRecorder

    rng = np.random.default_rng(1)
    chunks = [make_events(np.sort(rng.integers(0, 10**6, n)) * 100,
                          rng.integers(0, protocols.N_CHANNELS, n)) for n in (5, 0, 700, 33)]
    with SessionRecorder(tmp_path) as rec:
        for c in chunks:
            rec.on_events(c, 0.0)
        spool = list(tmp_path.glob(".skinhil-events.*.spool"))
        # on disk, not in memory (beyond one write buffer)
        assert len(spool) == 1 and spool[0].stat().st_size >= 738 * 11 - io.DEFAULT_BUFFER_SIZE
        assert rec.n_events == 738
        rec.on_marker(protocols.Marker(t_us=5, stimulus_id=2, phase=protocols.MarkerPhase.ONSET))
        out = rec.save(tmp_path / "session.npz", {"k": 1})
        assert np.array_equal(rec.events, np.concatenate(chunks))
    assert not list(tmp_path.glob(".skinhil-events.*"))  # the spool is gone
    with np.load(out, allow_pickle=False) as z:
        assert np.array_equal(z["events"], np.concatenate(chunks))
        assert z["markers"].tolist() == [(5, 2, "onset")]
        assert json.loads(str(z["meta"])) == {"k": 1} and z["decisions"].shape == (0,)


# -- answers inserted into the replayed stream ----------------------------------------------
def _board_units(encoder: Any, n: int) -> list[Any]:
    """``n`` flushes of a board's stream (events of 3 channels per ms, a marker every 10)."""
    out: list[Any] = []
    for k in range(n):
        ev = make_events(np.array([k * 1000, k * 1000, k * 1000 + 500]),
                         np.array([1, 2 + k % 300, 7]))
        out.append(encoder.events(ev, (k + 1) * 1000))
        if k % 10 == 0:
            out.append(encoder.marker(protocols.Marker(t_us=k * 1000, stimulus_id=k // 10,
                                                       phase=protocols.MarkerPhase.ONSET)))
    return out


@pytest.mark.parametrize("fd", [False, True])
def test_can_replay_stream_inserts_answers_with_an_unbroken_sequence(fd: bool) -> None:
    from skinhil.recording.replay_stream import CanReplayStream

    frames = [f for unit in _board_units(protocols.CanEncoder(fd=fd), 200) for f in unit]
    stream = CanReplayStream()
    answers = protocols.CanEncoder(fd=fd)
    played: list[protocols.CanFrame] = []
    for k, frame in enumerate(frames):
        if k % 37 == 5:  # a command arrived: its NACK goes before the next frame
            stream.answer(answers.ack(protocols.Ack(token=k, opcode=protocols.CommandCode.PING,
                                                    ok=False,
                                                    reason=protocols.NackReason.REPLAYING))[0])
        played += stream.out(frame)
    played += stream.flush()
    dec, ref = protocols.CanDecoder(fd=fd), protocols.CanDecoder(fd=fd)
    got, want = dec.feed(played), ref.feed(frames)
    acks = [r for r in got.records if isinstance(r, protocols.Ack)]
    assert len(acks) == stream.shift == len(range(5, len(frames), 37)) > 5
    assert all(a.reason == protocols.NackReason.REPLAYING for a in acks)
    assert dec.counters.seq_gaps == 0 and dec.counters.duplicates == 0
    assert np.array_equal(got.events, want.events)
    assert [r for r in got.records if not isinstance(r, protocols.Ack)] == want.records


def test_serial_replay_stream_inserts_answers_between_packets_of_any_chunking() -> None:
    """Units cut anywhere (a serial write holds any bytes): answers go in at packet
    boundaries only, and the stream decodes whole with an unbroken sequence."""
    from skinhil.recording.replay_stream import SerialReplayStream

    data = b"".join(_board_units(protocols.SerialEncoder(), 300))
    rng = np.random.default_rng(5)
    cuts = np.sort(rng.choice(np.arange(1, len(data)), 400, replace=False))
    units = [data[a:b] for a, b in zip([0, *cuts], [*cuts, len(data)], strict=True)]
    stream = SerialReplayStream()
    answers = protocols.SerialEncoder()
    played = []
    for k, unit in enumerate(units):
        if k % 23 == 3:
            stream.answer(answers.ack(protocols.Ack(token=k, opcode=protocols.CommandCode.PING,
                                                    ok=False,
                                                    reason=protocols.NackReason.REPLAYING)))
        played += stream.out(unit)
    played += stream.flush()
    assert b"".join(played[:1]) == units[0]  # as recorded until the first answer
    dec = protocols.SerialDecoder()
    got, want = dec.feed(b"".join(played)), decoded(data)
    acks = [r for r in got.records if isinstance(r, protocols.Ack)]
    assert [a.token for a in acks] == list(range(3, len(units), 23))
    c = dec.counters
    assert c.seq_gaps == 0 and c.duplicates == 0 and c.crc_errors == 0 and c.malformed == 0
    assert np.array_equal(got.events, want.events)
    assert [r for r in got.records if not isinstance(r, protocols.Ack)] == want.records


def test_a_killed_recording_leaves_the_previous_file_intact(tmp_path, pty_pair) -> None:
    rec = tmp_path / "kept.skcap"
    rec.write_bytes(b"the previous recording")
    reader = PtyReader(pty_pair.master)
    serve = ServeProcess("--port", pty_pair.path, "--record", str(rec), "--json")
    try:
        deadline = time.monotonic() + 120
        while not any(x.get("type") == "status" for x in serve.lines):
            assert time.monotonic() < deadline and not serve.exited, serve.stderr
            time.sleep(0.05)
        partial = list(tmp_path.glob(".kept.*.partial.skcap"))
        assert len(partial) == 1
        while partial[0].stat().st_size == 0:  # written as it goes (flushed every 0.5 s)
            assert time.monotonic() < deadline, serve.stderr
            time.sleep(0.05)
        serve.kill()  # SIGKILL: no chance to finish
    finally:
        serve.kill()
        reader.stop()
    assert rec.read_bytes() == b"the previous recording"
    with open(partial[0], "rb") as f, pytest.raises(ProtocolError, match="truncated"):
        read_header(f)
        list(read_units(f))  # the partial file is never taken for a whole recording
