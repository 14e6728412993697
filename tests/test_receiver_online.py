"""End to end: board subprocess → pty or vcan → receiver; online vs offline accuracy, faults.

Offline figures come from the same window definition as online: a simulated board stream
cut by the receiver's own onset detector, windows labelled by the marker they match;
accuracy = correct / scored markers under the one rule of :mod:`skinhil.receiver.scoring`
(missed onsets count as wrong, false alarms are reported but not scored), offline and online.
Two offline figures: the decoder on the very stream the board plays (its seed and schedule,
simulated offline: the same stimuli and noise, so online must match it within the issue's 5
points whatever the sampling error), and the decoder's cross-validated accuracy on its
training stream (another seed: a sampling error apart, bound max(5 points, 2 s.e.)).

Runs: 100 stimuli at the paper's 10 dB through the pty, 50 through vcan0, and 27 without
noise through vcan0, with 0.05 s rests (0.3 s per stimulus, ~31 s of real time per 100), and
short fault runs.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import protocols
from skinhil.receiver import Receiver, WindowDecoder
from skinhil.receiver.session import run_against_board, serve_command
from skinhil.receiver.training import (
    TrainingReport,
    stream_accuracy,
    stream_duration_s,
    stream_windows,
    train_decoder,
)
from skinhil.recording import SessionRecorder
from skinhil.transports import CanTransport, FaultParams, FaultyTransport, PtyMasterTransport

N_STIMULI = 100
N_VCAN_STIMULI = 50
"""Through vcan0 (inside user-mode Linux, several times slower): half the pty's run, the
same comparisons (two standard errors widen with the smaller count)."""
REST_S = 0.05
BOARD_SEED = 7
SNR_DB = 10.0
"""The paper's operating point."""
TOLERANCE = 0.05
"""The issue's bound on |online − offline| accuracy."""


@pytest.fixture(scope="session")
def decoder_10db() -> tuple[WindowDecoder, TrainingReport]:
    """A decoder trained at 10 dB on 180 board-like stimuli and its offline report."""
    decoder, report = train_decoder(SNR_DB, reps=20, seed=0, rest_s=REST_S)
    return WindowDecoder(decoder), report


@pytest.fixture(scope="session")
def decoder_inf() -> tuple[WindowDecoder, TrainingReport]:
    """A decoder trained without noise on 45 board-like stimuli and its offline report."""
    decoder, report = train_decoder(math.inf, reps=5, seed=0, rest_s=REST_S)
    return WindowDecoder(decoder), report


def play(receiver: Receiver, link_args: list[str], snr_db: float, n_stimuli: int) -> None:
    """A board on ``link_args`` plays ``n_stimuli`` stimuli into ``receiver`` until it ends;
    the receiver's transport is shut down after."""
    try:
        status, _, err = run_against_board(
            receiver, serve_command(link_args, stream_duration_s(n_stimuli, REST_S), snr_db,
                                    BOARD_SEED, REST_S))
    finally:
        receiver.transport.shutdown()
    assert status == 0, err


def run_pty(decoder: WindowDecoder, snr_db: float, n_stimuli: int,
            faults: FaultParams | None = None, recorder: SessionRecorder | None = None
            ) -> tuple[Receiver, FaultyTransport | None]:
    link, slave_fd = PtyMasterTransport.open_pair()
    transport = link if faults is None else FaultyTransport(link, faults, keep_clean=True)
    receiver = Receiver(transport, decoder, listeners=[recorder] if recorder else [])
    try:
        play(receiver, ["--port", link.slave_path], snr_db, n_stimuli)
    finally:
        os.close(slave_fd)
    return receiver, (transport if faults is not None else None)


def describe(where: str, receiver: Receiver, offline: TrainingReport) -> str:
    sb = receiver.scoreboard
    return (f"\n{where} {offline.snr_db:g} dB: offline {offline.accuracy:.3f} "
            f"({offline.markers} stimuli, {offline.misses} missed, {offline.false_alarms} false "
            f"alarms), online {sb.accuracy:.3f} ({sb.scored} stimuli, {sb.misses} missed, "
            f"{sb.false_alarms} false alarms, {receiver.link_report().late_events} late events)")


def check_online_matches_offline(where: str, receiver: Receiver, decoder: WindowDecoder,
                                  trained: TrainingReport, snr_db: float = SNR_DB,
                                  n_stimuli: int = N_STIMULI, against_cv: bool = True) -> None:
    """The issue's comparison at ``snr_db`` over ``n_stimuli`` stimuli (module docstring);
    ``against_cv``: also against the decoder's cross-validated accuracy."""
    replay = stream_windows(n_stimuli, snr_db, REST_S, seed=0, balanced=False,
                            board_seed=BOARD_SEED)
    offline = stream_accuracy(decoder.decoder, replay)
    sb = receiver.scoreboard
    print(describe(where, receiver, trained)
          + f"; offline on the board's own stream {offline:.3f} ({replay.markers} stimuli, "
            f"{replay.misses} missed, {replay.false_alarms} false alarms)")
    assert sb.scored >= n_stimuli - 1
    assert sb.accuracy > 3 / 9                        # well above chance (1/9): not vacuous
    assert abs(sb.accuracy - offline) <= TOLERANCE
    if not against_cv:
        return
    # two binomial estimates (100 online, 180 cross-validated stimuli at p ≈ 0.7) differ by
    # ~0.06 (one standard error) by chance alone: here the bound is the larger of the
    # issue's 5 points and two standard errors of the difference (docs/receiver.md)
    p = trained.accuracy
    se = math.sqrt(p * (1 - p) * (1 / sb.scored + 1 / trained.markers))
    assert abs(sb.accuracy - p) <= max(TOLERANCE, 2 * se)


def test_online_accuracy_through_a_pty_matches_offline_at_10_db(decoder_10db):
    decoder, trained = decoder_10db
    receiver, _ = run_pty(decoder, SNR_DB, N_STIMULI)
    check_online_matches_offline("pty", receiver, decoder, trained)


def test_fault_injection_is_survived_and_accounted(decoder_inf, tmp_path):
    decoder, _ = decoder_inf
    n = 30
    clean, _ = run_pty(decoder, math.inf, n)
    recorder = SessionRecorder(tmp_path)  # its spool file goes with tmp_path
    receiver, faulty = run_pty(decoder, math.inf, n,
                               FaultParams(drop_p=0.01, corrupt_byte_p=2e-3, seed=11),
                               recorder)
    assert faulty is not None
    inj, link = faulty.injected, receiver.link_report()
    # what was sent, decoded from the bytes before the faults
    sent = protocols.SerialDecoder()
    sent_result = sent.feed(b"".join(faulty.clean))
    sb, sb0 = receiver.scoreboard, clean.scoreboard
    print(f"\nfaults: {inj.units_seen} packets, {inj.units_dropped} dropped, "
          f"{inj.corrupted_units} corrupted ({inj.bytes_corrupted} bytes); receiver: "
          f"{link.frames_lost} frames lost, {link.crc_errors} CRC errors, "
          f"{link.lost_on_link} events lost of {sent.counters.events_decoded} "
          f"({link.untimed_events} untimed); accuracy {sb0.accuracy:.3f} clean, "
          f"{sb.accuracy:.3f} faulty ({sb.scored} vs {sb0.scored} stimuli scored)")
    assert inj.corrupted_units > 0 and inj.units_dropped > 0
    assert link.link_errors == 0
    # exact by the protocol: every dropped or corrupted packet is one frame missing from
    # the sequence numbers once a later frame arrives (the damaged packets at the very end
    # of the stream, if any, have none after them: they show as CRC errors only), and the
    # events lost are those of the damaged packets
    damaged = inj.units_dropped + inj.corrupted_units
    last = inj.units_seen - 1
    trailing = sum(1 for k, i in enumerate(reversed(inj.damaged_units)) if i == last - k)
    assert len(inj.damaged_units) == damaged
    assert link.frames_lost == damaged - trailing
    assert sent.counters.frames_ok - link.frames_ok == damaged
    assert link.lost_on_link == sent.counters.events_decoded - link.events_decoded
    # graceful: errors only where data were lost — a stimulus is "hit" when its marker was
    # lost or an event of its scoring span (match window + decision window) was
    got = {(int(e["t"]), int(e["addr"])) for e in recorder.events}
    lost_t = np.array(sorted(int(e["t"]) for e in sent_result.events
                             if (int(e["t"]), int(e["addr"])) not in got))
    received = {int(t) for t in recorder.markers["t_us"]}
    span_us = sb.match_window_us  # the match window includes the decision window
    hit = 0
    for rec in sent_result.records:
        if isinstance(rec, protocols.Marker) and rec.phase == protocols.MarkerPhase.ONSET:
            t = int(rec.t_us)
            in_span = np.any((lost_t >= t) & (lost_t <= t + span_us)) if lost_t.size else False
            hit += int(t not in received or bool(in_span))
    print(f"stimuli hit by the faults: {hit}")
    assert sb.scored >= sb0.scored - hit
    assert sb.scored - sb.correct <= sb0.scored - sb0.correct + hit


def run_vcan(decoder: WindowDecoder, snr_db: float, n_stimuli: int,
             bitrate: int = 1_000_000) -> Receiver:
    receiver = Receiver(CanTransport("vcan0", bitrate=bitrate), decoder)
    play(receiver, ["--can", "vcan0", "--bitrate", str(bitrate)], snr_db, n_stimuli)
    return receiver


@pytest.mark.vcan
def test_online_accuracy_through_vcan_matches_offline_at_10_db():
    """The issue's test through vcan0 at 1 Mbit/s: at 10 dB the board sends a few hundred
    events/s, well within the bus. Against the decoder on the board's own stream simulated
    offline; the comparison with the cross-validated accuracy is the pty's (a decoder trained
    on 180 stimuli inside user-mode Linux took 30 s of the CI's budget: this one learns 90
    without cross-validation)."""
    decoder, trained = train_decoder(SNR_DB, reps=10, seed=0, rest_s=REST_S,
                                     cross_validation=False)
    receiver = run_vcan(WindowDecoder(decoder), SNR_DB, N_VCAN_STIMULI)
    check_online_matches_offline("vcan", receiver, WindowDecoder(decoder), trained,
                                 n_stimuli=N_VCAN_STIMULI, against_cv=False)


@pytest.mark.vcan
def test_online_accuracy_through_vcan_matches_offline_without_noise(decoder_inf):
    """Without noise: 27 stimuli through vcan0 against the decoder on the board's own stream
    simulated offline. Not against its cross-validated accuracy: that is 1.0 on its 45
    training stimuli, a figure with no spread to bound by, while on the board's stream
    (another sequence of the same stimuli) the same decoder errs now and then offline too."""
    decoder, trained = decoder_inf
    receiver = run_vcan(decoder, math.inf, 27)
    check_online_matches_offline("vcan", receiver, decoder, trained,
                                 snr_db=math.inf, n_stimuli=27, against_cv=False)


@pytest.mark.vcan
def test_dropped_can_frames_equal_the_sequence_gaps(decoder_inf):
    decoder, _ = decoder_inf
    bus = FaultyTransport(CanTransport("vcan0"), FaultParams(drop_p=0.01, seed=2),
                          keep_clean=True)
    receiver = Receiver(bus, decoder)
    play(receiver, ["--can", "vcan0"], math.inf, 10)
    link = receiver.link_report()
    assert bus.injected.units_dropped > 0
    assert link.frames_lost == bus.injected.units_dropped
    sent = protocols.CanDecoder(board_id=0)
    sent.feed([f for payload in bus.clean for f in payload])
    assert link.lost_on_link == sent.counters.events_decoded - link.events_decoded
    assert np.isfinite(receiver.scoreboard.accuracy)
