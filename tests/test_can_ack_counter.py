"""The ACK counter of CAN ACK frames (SPEC.md §5.6): ACKs lost in a block of frames that is
a whole number of classic sequence periods (16 frames) leave the frame sequence without a
gap, and are still counted exactly; a board that sends 0 in every ACK (before the counter
existed) counts nothing."""

from __future__ import annotations

import numpy as np

import protocols
from protocols.events import make_events


def _stream(fd: bool) -> tuple[list[protocols.CanFrame], protocols.CanEncoder]:
    enc = protocols.CanEncoder(fd=fd)
    frames: list[protocols.CanFrame] = []
    for k in range(100):
        frames += enc.events(make_events(np.arange(40) * 100 + k * 10_000, np.arange(40)),
                             (k + 1) * 10_000)
        frames += enc.ack(protocols.Ack(k, protocols.CommandCode.DECISION, True))
    return frames, enc


def test_acks_lost_in_whole_sequence_periods_are_counted() -> None:
    frames, _ = _stream(fd=False)
    dec = protocols.CanDecoder()
    kept = frames[:100] + frames[100 + 16 * 40:]  # 640 frames gone: 40 periods of 16
    acks = [r for r in dec.feed(kept).records if isinstance(r, protocols.Ack)]
    assert dec.counters.frames_lost == 0  # the frame sequence cannot see it
    assert dec.counters.acks_lost > 0
    assert len(acks) + dec.counters.acks_lost == 100
    assert all(a.ok for a in acks)


def test_a_board_without_the_counter_counts_nothing() -> None:
    frames, _ = _stream(fd=True)
    old = [protocols.CanFrame(f.arbitration_id, f.data[:1] + bytes([f.data[1] & 1])
                              + f.data[2:], f.is_fd)
           if f.arbitration_id >> 4 == 2 else f for f in frames]  # ACK byte 1: ok only
    dec = protocols.CanDecoder(fd=True)
    acks = [r for r in dec.feed(old[:50] + old[150:]).records if isinstance(r, protocols.Ack)]
    assert len(acks) < 100 and dec.counters.acks_lost == 0
