"""The notebook API (docs/api.md): its examples run as written, a board's thread error reaches
the caller, commands are answered, and a receiver that joins late says what it missed."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from harness.golden import GOLDEN_DIR
from harness.serve import RUN_DIR, serve_env

import protocols
import skinhil
from skinhil.errors import TransportError

DOCS = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def examples() -> list[str]:
    """The python blocks of docs/api.md, in order."""
    return re.findall(r"```python\n(.*?)```", DOCS.read_text(encoding="utf-8"), re.S)


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], cwd=RUN_DIR, env=serve_env(),
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout


def test_first_example_runs_as_written() -> None:
    code = examples()[0]
    assert "skinhil.Board(size=(6, 6), snr_db=10, seed=1, duration_s=3)" in code
    received, sent = map(int, _run(code).split())
    assert 0 < received <= sent  # 2 s of a 3 s run, every event of them


def test_suite_example_scores_the_answer() -> None:
    last = _run(examples()[1]).strip().splitlines()[-1]
    assert int(last) == 1  # the one ANSWER sent reached the task scoreboard


def test_a_decision_is_acknowledged_and_scored() -> None:
    with skinhil.Board(snr_db=10, seed=2, duration_s=1.0) as board:
        with skinhil.Receiver(board.peer) as rx:
            token = rx.decide(3, confidence=0.9)
            grip = rx.grip(1.0)
            deadline = time.monotonic() + 5
            while (rx.ack(token) is None or rx.ack(grip) is None) \
                    and time.monotonic() < deadline:
                time.sleep(0.02)
            assert rx.ack(token).ok
            assert rx.ack(grip).reason == protocols.NackReason.NO_OBJECT  # nothing held
            assert rx.commands() == {"sent": 2, "unsent": 0, "acked": 1, "nacked": 1,
                                     "unanswered": 0}
            batches = list(rx.batches(timeout_s=0.3))
            assert all(b.dtype == skinhil.EVENT_DTYPE for b in batches)
        assert board.wait(10)
    assert board.score()["decisions"] == 1
    assert board.summary()["events_sent"] > 0


def test_an_error_in_the_board_thread_is_raised_in_the_caller() -> None:
    board = skinhil.Board(snr_db=10, seed=3)
    board.transport.shutdown()  # the link goes away under the running board
    with pytest.raises(TransportError, match="closed"):
        board.wait(10)
    assert not board.running
    board.close()  # raised once, closing again is quiet


def test_a_late_receiver_counts_what_the_board_sent_before_it_joined() -> None:
    """The golden serial capture decoded from a third of the way in: the events before the
    first status are the board's, not lost on the link; after it only events that came before
    the first sync (untimed, which SPEC.md §7 counts lost) are lost; every event is accounted
    for."""
    stream = (GOLDEN_DIR / "serial.bin").read_bytes()
    decoder = protocols.SerialDecoder()
    status = None
    result = decoder.feed(stream[len(stream) // 3:])
    for rec in result.records:
        if isinstance(rec, protocols.Status):
            status = rec
    c = decoder.counters
    assert status is not None and c.events_lost <= c.events_untimed
    assert c.frames_lost == c.crc_errors == c.seq_gaps == 0
    assert c.events_before_join > 0
    assert c.events_before_join + c.events_decoded + c.events_lost == status.events_sent


def test_a_receiver_that_joins_a_running_board_late_says_what_it_missed() -> None:
    """On UDP (datagrams sent before a receiver listens are gone): the events the board had
    sent before the receiver's first status are counted apart, not as lost on the link."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with skinhil.Board(snr_db=10, seed=4, link=f"udp:127.0.0.1:{port}"):
        time.sleep(1.0)  # the board runs with nobody listening
        with skinhil.Receiver(f"udp:{port}") as rx:
            deadline = time.monotonic() + 10
            while rx.status is None and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.5)
            link = rx.link_report()
    assert link["sent_before_join"] > 0
    # every event the board sent up to its last status: missed before, decoded or lost after
    assert (link["sent_before_join"] + link["events_decoded"] + link["lost_on_link"]
            >= link["board_sent"] > link["events_decoded"])
