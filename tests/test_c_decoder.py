"""The reference decoder in C (examples/skin_decoder.c), built with the system compiler:
it outputs what every conformance vector says (protocols/conformance.json), and against
``skinhil serve --score`` on a pair of ptys from ``skinhil pty`` it counts every event the
board's final STATUS says it sent, sees the RUN_END record and its DECISIONs are scored."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from harness.serve import REPO, RUN_DIR, run_serve, serve_env
from protocol_examples import RUN_END, SESSION_RECORDS, distinct_events

import protocols

SOURCE = REPO / "examples" / "skin_decoder.c"
DURATION_S = 20.0
"""Board time of the live run (s): about 40 stimuli of the default random schedule."""


@pytest.fixture(scope="module")
def decoder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example built with the system C compiler, warnings as errors."""
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "no C compiler: apt-get install gcc (.ci/run does)"
    out = tmp_path_factory.mktemp("c") / "skin_decoder"
    subprocess.run([cc, "-std=c11", "-D_DEFAULT_SOURCE", "-O2", "-Wall", "-Wextra", "-Werror",
                    "-o", str(out), str(SOURCE), "-lm"], check=True, capture_output=True)
    return out


def _lines(text: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_c_decoder_outputs_every_conformance_vector(decoder: Path) -> None:
    doc = json.loads(protocols.CONFORMANCE_PATH.read_text(encoding="utf-8"))
    for case in doc["cases"]:
        run = subprocess.run([str(decoder), "--stdin"], input=bytes.fromhex(case["input"]),
                             capture_output=True, timeout=10, check=True)
        out = _lines(run.stdout.decode("utf-8"))
        assert [x["event"] for x in out if "event" in x] == case["events"], case["name"]
        assert [x["record"] for x in out if "record" in x] == case["records"], case["name"]
        assert out[-1] == {"counters": case["counters"]}, case["name"]


def test_c_decoder_against_serve_on_a_pty(decoder: Path, tmp_path: Path) -> None:
    score = tmp_path / "score.json"
    pty = subprocess.Popen([sys.executable, "-m", "skinhil", "pty", "--quiet"], cwd=RUN_DIR,
                           env=serve_env(), stdout=subprocess.PIPE, text=True)
    dut = None
    try:
        assert pty.stdout is not None
        board_end, host_end = pty.stdout.readline().strip(), pty.stdout.readline().strip()
        dut = subprocess.Popen([str(decoder), "--tty", host_end], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        board = run_serve("--port", board_end, "--duration", str(DURATION_S), "--seed", "3",
                          "--score", str(score), "--markers", "--json", timeout_s=DURATION_S + 60)
        assert board.returncode == 0, board.stderr
        out, err = dut.communicate(timeout=20)  # it ends by itself at the RUN_END record
    finally:
        for p in (dut, pty):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    assert dut.returncode == 0, err
    got = _lines(out)[-1]
    summary = next(x for x in _lines(board.stdout) if x.get("type") == "summary")
    s = json.loads(score.read_text())
    c, status = got["counters"], got["status"]
    print(f"\nC decoder: {c['events_decoded']} events, status sent {status['events_sent']}, "
          f"{got['decisions']} decisions; board scored {s['decisions']} ({s['right']} right, "
          f"{s['wrong']} wrong, {s['misses']} missed)")
    # the same events as the board's final STATUS, none lost, nothing damaged
    assert c["events_decoded"] == status["events_sent"] == summary["sent"] > 5_000
    assert c["events_lost"] == 0 and c["crc_errors"] == c["malformed"] == c["seq_gaps"] == 0
    assert status["events_queued"] == 0 and status["t_us"] == DURATION_S * 1e6
    # the session configured it; the run's end came on the wire
    assert got["session"] == {"seen": 1, "n_channels": 338, "n_stimuli": 14,
                              "table_digest": got["session"]["table_digest"]}
    assert got["run_end"] == 1 and got["run_end_reason"] == int(protocols.RunEndReason.DURATION)
    # every DECISION it sent reached the board and was scored
    assert got["decisions"] == s["decisions"] >= 20
    assert s["matched"] + s["late"] + s["false_alarms"] + s["duplicates"] == s["decisions"]
    assert s["right"] > s["decisions"] / 9  # above chance (1 in 9)


def test_c_decoder_over_udp_learns_decides_and_answers_the_sender(decoder: Path) -> None:
    """UDP (SPEC §10): a stream of two touches of the same channels in datagrams of whole
    packets; a MARKER labels the first (id 3), so the second is answered with a DECISION
    for stimulus 3, sent back to the datagrams' source; the RUN_END ends the decoder."""
    rng = np.random.default_rng(0)
    t = [*range(0, 600_000, 10_000)]  # a quiet background: one event every 10 ms
    a = [int(x) for x in rng.integers(200, 338, len(t))]
    for onset in (100_000, 400_000):  # two touches: 30 events on channels 0..29 in 3 ms
        t += [onset + 100 * (i % 30) for i in range(30)]
        a += list(range(30))
    ev = distinct_events(t, a)
    enc = protocols.SerialEncoder()
    first = ev["t"] < 100_000
    stream = (b"".join(enc.session_record(r) for r in SESSION_RECORDS)
              + enc.events(ev[first], 100_000)
              + enc.marker(protocols.Marker(100_000, 3, protocols.MarkerPhase.ONSET))
              + enc.events(ev[~first], 600_000) + enc.session_record(RUN_END))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    port_probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    port_probe.bind(("127.0.0.1", 0))
    port = port_probe.getsockname()[1]
    port_probe.close()
    dut = subprocess.Popen([str(decoder), "--udp", f"127.0.0.1:{port}"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)  # bound
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(10)
        packets = [p + b"\0" for p in stream.split(b"\0")[:-1]]
        for i in range(0, len(packets), 8):  # datagrams of whole packets
            sock.sendto(b"".join(packets[i:i + 8]), ("127.0.0.1", port))
            time.sleep(0.002)
        answer = protocols.SerialDecoder().feed(sock.recv(2048)).records
        out, err = dut.communicate(timeout=10)
    finally:
        sock.close()
        if dut.poll() is None:
            dut.kill()
            dut.wait()
    assert len(answer) == 1 and isinstance(answer[0], protocols.Decision), answer
    assert answer[0].stimulus_id == 3 and answer[0].confidence is not None
    assert answer[0].confidence > 0.9
    got = _lines(out)[-1]
    assert got["counters"]["events_decoded"] == len(ev) and got["decisions"] == 1
    assert got["counters"]["seq_gaps"] == got["counters"]["crc_errors"] == 0
    assert got["run_end"] == 1 and got["session"]["n_stimuli"] == 2, err
