"""End to end: board subprocess → pty or vcan → receiver; online vs offline accuracy, faults.

100 stimuli per run with 0.05 s rests (0.3 s each, ~30 s of real time per run).
"""

from __future__ import annotations

import math
import os

import pytest

from firmware_sim.transport import CanTransport
from skinhil.receiver import FaultParams, FaultyTransport, Receiver, WindowDecoder
from skinhil.receiver.pty_link import PtyMasterTransport
from skinhil.receiver.session import run_against_board, serve_command
from skinhil.receiver.training import train_decoder

N_STIMULI = 100
REST_S = 0.05
DURATION_S = 0.1 + N_STIMULI * (0.25 + REST_S)
TOLERANCE = 0.05

_trained: dict[float, tuple[WindowDecoder, float]] = {}


def trained(snr_db: float) -> tuple[WindowDecoder, float]:
    """A decoder at ``snr_db`` and its offline cross-validated accuracy (cached per run)."""
    if snr_db not in _trained:
        decoder, report = train_decoder(snr_db, reps=30, seed=0)
        _trained[snr_db] = (WindowDecoder(decoder), report.cv_accuracy)
    return _trained[snr_db]


def run_pty(decoder: WindowDecoder, snr_db: float, duration_s: float,
            faults: FaultParams | None = None) -> tuple[Receiver, FaultyTransport | None]:
    link, slave_fd = PtyMasterTransport.open_pair()
    transport = link if faults is None else FaultyTransport(link, faults)
    receiver = Receiver(transport, decoder)
    try:
        status, _, err = run_against_board(
            receiver, serve_command(["--port", link.slave_path], duration_s, snr_db, 7, REST_S))
    finally:
        transport.shutdown()
        os.close(slave_fd)
    assert status == 0, err
    return receiver, (transport if faults is not None else None)


@pytest.mark.parametrize("snr_db", [10.0, math.inf])
def test_online_accuracy_through_a_pty_matches_offline(snr_db):
    decoder, offline = trained(snr_db)
    receiver, _ = run_pty(decoder, snr_db, DURATION_S)
    sb = receiver.scoreboard
    print(f"\n{snr_db} dB: offline CV {offline:.3f}, online (pty) {sb.accuracy:.3f} over "
          f"{sb.scored} stimuli, {sb.misses} missed, {sb.false_alarms} false alarms")
    assert sb.scored >= N_STIMULI - 1
    assert abs(sb.accuracy - offline) <= TOLERANCE


def test_fault_injection_is_survived_and_accounted():
    decoder, _ = trained(math.inf)
    clean, _ = run_pty(decoder, math.inf, 6.1)
    receiver, faulty = run_pty(decoder, math.inf, 6.1,
                               FaultParams(drop_p=0.01, corrupt_byte_p=2e-4, seed=11))
    assert faulty is not None
    inj, link = faulty.injected, receiver.link_report()
    assert inj.bytes_corrupted > 0 and inj.units_dropped > 0
    assert link.crc_errors > 0                        # corrupted packets were detected
    assert link.lost_on_link > 0                      # and the loss is reported, not hidden
    assert link.events_decoded + link.lost_on_link == link.board_sent
    assert receiver.scoreboard.scored == clean.scoreboard.scored
    assert receiver.scoreboard.accuracy >= clean.scoreboard.accuracy - 0.25


@pytest.mark.vcan
def test_online_accuracy_through_vcan_matches_offline():
    snr_db = 10.0
    decoder, offline = trained(snr_db)
    bus = CanTransport("vcan0")
    receiver = Receiver(bus, decoder)
    try:
        status, _, err = run_against_board(
            receiver, serve_command(["--can", "vcan0"], DURATION_S, snr_db, 7, REST_S))
    finally:
        bus.shutdown()
    assert status == 0, err
    sb = receiver.scoreboard
    print(f"\nvcan {snr_db} dB: offline CV {offline:.3f}, online {sb.accuracy:.3f}")
    assert abs(sb.accuracy - offline) <= TOLERANCE


@pytest.mark.vcan
def test_dropped_can_frames_equal_the_sequence_gaps():
    decoder, _ = trained(math.inf)
    bus = FaultyTransport(CanTransport("vcan0"), FaultParams(drop_p=0.01, seed=2))
    receiver = Receiver(bus, decoder)
    try:
        status, _, err = run_against_board(
            receiver, serve_command(["--can", "vcan0"], 3.1, math.inf, 7, REST_S))
    finally:
        bus.shutdown()
    assert status == 0, err
    assert bus.injected.units_dropped > 0
    assert receiver.link_report().frames_lost == bus.injected.units_dropped
