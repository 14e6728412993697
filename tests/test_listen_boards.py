"""``skinhil listen --udp`` decodes two ``skinhil serve --udp`` boards on one port of
127.0.0.1 at once, as a user would run them: per-board summaries and a combined view whose
counters are exact."""

from __future__ import annotations

import errno
import math
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from harness.lab import LOOPBACK_LSL_CFG
from harness.serve import RUN_DIR, ServeProcess, serve_env

from skinhil.decoding.model_file import save_decoder
from skinhil.process_output import SUMMARY, last_record, records
from skinhil.receiver.training import train_decoder


def _bound(port: int) -> bool:
    """Whether something already listens on UDP 127.0.0.1:port."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError as exc:
            return exc.errno == errno.EADDRINUSE
    return False


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _listen_to_two_boards(tmp_path: Path, *listen_args: str) -> tuple[dict, list[int], str]:
    """Run ``listen --udp`` (with ``listen_args``) and two ``serve --udp`` boards sending to
    it; return listen's JSON summary, the boards' generated counts (board seed 1, 2) and
    listen's stderr."""
    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False)
    model = tmp_path / "model.npz"
    save_decoder(decoder, model)
    port = _free_port()
    listen = subprocess.Popen(
        [sys.executable, "-m", "skinhil", "listen", "--udp", f"127.0.0.1:{port}", "--model",
         str(model), "--json", *listen_args], cwd=RUN_DIR, env=serve_env(),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    boards = []
    try:
        end = time.monotonic() + 60
        while not _bound(port):
            assert listen.poll() is None and time.monotonic() < end, listen.stderr
            time.sleep(0.05)
        boards = [ServeProcess("--udp", f"127.0.0.1:{port}", "--duration", "1.5", "--seed",
                               str(seed), "--json") for seed in (1, 2)]
        for b in boards:
            assert b.wait(60) == 0, b.stderr
        time.sleep(0.5)
        listen.send_signal(signal.SIGINT)
        out, err = listen.communicate(timeout=30)
    finally:
        for b in boards:
            b.kill()
        if listen.poll() is None:
            listen.kill()
    assert listen.returncode == 130, err  # stopped cleanly by Ctrl-C, after its summary
    summary = last_record(records(out), SUMMARY)
    assert summary is not None, out
    return summary, [b.summary()["generated"] for b in boards], err


def test_listen_decodes_two_udp_boards_at_once(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Both boards decoded whole, with the live view and LSL outlets on: one view server for
    both, each board its LSL streams (the second one's named NAME-2-...)."""
    cfg = tmp_path / "lsl_api.cfg"
    cfg.write_text(LOOPBACK_LSL_CFG)
    monkeypatch.setenv("LSLAPICFG", str(cfg))  # liblsl on 127.0.0.1 only
    summary, generated, err = _listen_to_two_boards(tmp_path, "--view", "0", "--lsl", "two")
    generated = sorted(generated)
    per_board = summary["boards"]
    assert len(per_board) == 2
    assert summary["refused_datagrams"] == 0
    assert sorted(s["link"]["events_decoded"] for s in per_board.values()) == generated
    assert sorted(s["link"]["board_generated"] for s in per_board.values()) == generated
    link = summary["link"]
    assert link["events_decoded"] == sum(generated) > 0
    assert link["lost_on_link"] == link["frames_lost"] == link["crc_errors"] == 0
    assert err.count("live view at") == 1, err
    named = sorted(line.split("LSL outlets ")[1].split("-spikes")[0]
                   for line in err.splitlines() if "LSL outlets" in line)
    assert named == ["two", "two-2"], err
    for key in per_board:
        assert f"(board {key})" in err


def test_listen_refuses_sources_past_its_cap(tmp_path: Path) -> None:
    """``--udp-max-sources 1``: the first board is decoded whole, the second one's datagrams
    are refused and counted, never a board of their own."""
    summary, generated, _ = _listen_to_two_boards(tmp_path, "--udp-max-sources", "1")
    per_board = summary["boards"]
    assert len(per_board) == 1
    decoded = next(iter(per_board.values()))["link"]
    assert decoded["events_decoded"] == decoded["board_generated"] in generated
    assert summary["refused_datagrams"] > 0
