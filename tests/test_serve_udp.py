"""``skinhil serve --udp`` on loopback (127.0.0.1): whole packets in every datagram, every
event and marker arrives, commands are answered, and the loss accounting is exact; the 6x6
skin in the narrow format (version 3) and a 32x32 skin (15,730 channels) in the wide one; a
board on two threads (``--threads 2``) streams what one thread does and answers commands; a
board on one core (``--cpu N``) runs there alone."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from harness.peers import UdpPeer
from harness.serve import ServeProcess

import protocols
from skinhil.receiver.training import board_stream


@pytest.mark.parametrize(("size", "version", "duration_s"),
                         [("6x6", 3, 2.5), ("32x32", 4, 1.0), ("3x3", 3, 1.5),
                          ("5x6", 3, 1.5)])
def test_serve_udp_stream_is_complete_and_exact(size: str, version: int,
                                                duration_s: float) -> None:
    peer = UdpPeer(versions=(version,))  # the other version would raise ProtocolError
    serve = ServeProcess("--udp", f"127.0.0.1:{peer.port}", "--size", size, "--duration",
                         str(duration_s), "--seed", "4", "--rest", "0.05", "--json",
                         "--snr-db", "inf")  # noise-free: a 32x32 board keeps real time
    try:
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 60)
        assert not serve.exited, serve.stderr
        token = peer.command(protocols.CommandCode.PING)
        assert serve.wait(120) == 0, serve.stderr
        assert peer.wait_for(lambda p: p.decoder.counters.frames_ok > 0, 1)
    finally:
        serve.kill()
        peer.close()
    assert set(peer.datagram_ends) == {0}  # every datagram ends a packet
    ev = peer.events
    summary = serve.summary()
    final = peer.of(protocols.Status)[-1]
    c = peer.decoder.counters
    assert len(ev) > 0 and np.all(np.diff(ev["t"]) >= 0)
    if version == 4:
        assert ev["addr"].max() >= protocols.N_CHANNELS  # addresses only the wide words carry
    assert summary["generated"] == final.events_generated == final.events_sent == len(ev)
    assert c.frames_lost == 0 and c.events_lost == 0 and c.crc_errors == 0
    assert len(peer.of(protocols.Marker)) == summary["markers_sent"] > 0
    assert [a.ok for a in peer.of(protocols.Ack) if a.token == token] == [True]


@contextmanager
def _udp_board(*args: str) -> Iterator[tuple[UdpPeer, ServeProcess]]:
    """``skinhil serve --udp ARGS --json`` into a UdpPeer; when the block ends the board has
    finished and every event it sent is decoded."""
    peer = UdpPeer(versions=(4,))
    serve = ServeProcess("--udp", f"127.0.0.1:{peer.port}", "--json", *args)
    try:
        yield peer, serve
        assert serve.wait(120) == 0, serve.stderr
        sent = serve.summary()["sent"]
        assert peer.wait_for(lambda p: len(p.events) >= sent, 2)
    finally:
        serve.kill()
        peer.close()


def _udp_run(*args: str) -> tuple[np.ndarray, list[tuple[int, int, int]], dict[str, Any]]:
    with _udp_board(*args) as (peer, serve):
        pass
    markers = [(m.t_us, m.stimulus_id, m.phase) for m in peer.of(protocols.Marker)]
    return peer.events, markers, serve.summary()


def test_serve_two_threads_stream_the_same_events() -> None:
    """``--threads 2`` (neurons two ticks behind the mechanics, on a thread of their own)
    streams exactly the events and markers of one thread: same times, same channels, and the
    board time and the accounting end where they do; and both stream exactly what the same
    seed gives offline (the board's warm-up leaves the noise streams where they were)."""
    args = ("--size", "16x16", "--duration", "1.5", "--seed", "6", "--rest", "0.05",
            "--snr-db", "10")
    one = _udp_run(*args)
    two = _udp_run(*args, "--threads", "2")
    for ev, _, summary in (one, two):
        assert summary["board_time_s"] == 1.5 and summary["dropped"] == 0
        assert summary["generated"] == summary["sent"] == len(ev) > 0
    assert np.array_equal(one[0], two[0])
    assert one[1] == two[1] and len(one[1]) > 0
    blocks = list(board_stream(1.5, 10.0, 0.05, 6, size=(16, 16)))
    offline = np.concatenate([ev for ev, _, _ in blocks])
    assert np.array_equal(one[0]["t"], offline["t"])
    assert np.array_equal(one[0]["addr"], offline["addr"])
    assert [(t, i, phase.name.lower()) for t, i, phase in one[1]] == [
        (m.t_us, m.stimulus_id, m.phase) for _, ms, _ in blocks for m in ms]


def test_serve_two_threads_answers_commands_and_keeps_the_account() -> None:
    """Host commands reach a pipelined board (``--threads 2``): a new SNR and a stimulus
    started by the host are acknowledged, the stimulus' onset marker arrives after every event
    before its time, and every status closes the account."""
    with _udp_board("--size", "12x12", "--threads", "2", "--host-driven", "--duration",
                    "2.0") as (peer, serve):
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 60)
        assert not serve.exited, serve.stderr
        codes = protocols.CommandCode
        t_snr = peer.command(codes.SET_SNR, 0.0)
        t_stim = peer.command(codes.SET_STIMULUS, 10)  # paper stimulus A
    acks = {a.token: a for a in peer.of(protocols.Ack)}
    assert acks[t_snr].ok and acks[t_stim].ok
    onsets = [m for m in peer.of(protocols.Marker) if m.stimulus_id == 10
              and m.phase == protocols.MarkerPhase.ONSET]
    assert len(onsets) == 1
    i_onset = peer.records.index(onsets[0])
    before = peer.events[: peer.events_before[i_onset]]
    assert len(before) == 0 or before["t"].max() < onsets[0].t_us
    assert np.any(peer.events["t"] >= onsets[0].t_us)  # the press and the noise fire
    for st in peer.of(protocols.Status):
        assert st.events_generated == st.events_sent + st.events_dropped + st.events_queued
    assert serve.summary()["generated"] == serve.summary()["sent"] == len(peer.events)


def test_serve_cpu_runs_the_board_on_that_core_alone() -> None:
    """``--cpu N`` pins the board (all its threads) to core N and streams as without it."""
    core = max(os.sched_getaffinity(0))
    args = ("--size", "16x16", "--duration", "1.5", "--seed", "6", "--rest", "0.05",
            "--snr-db", "10")
    pinned: list[set[int]] = []
    with _udp_board(*args, "--cpu", str(core)) as (peer, serve):
        assert peer.wait_for(lambda p: p.of(protocols.Status) or serve.exited, 60)
        for task in Path(f"/proc/{serve.proc.pid}/task").iterdir():  # every thread
            pinned.append(os.sched_getaffinity(int(task.name)))
    assert pinned and all(cores == {core} for cores in pinned), pinned
    assert np.array_equal(peer.events, _udp_run(*args)[0])
