"""A decoder under test written from protocols/SPEC.md alone: it reads a skinhil board's
stream, tells which stimulus it feels, and answers the board with a DECISION.

Uses only the ``protocols`` package (the codecs) and pyserial or python-can (the link):
no skinhil model, board or receiver code. The rule, in board time (µs, from the stream):

1. onset: a 5 ms bin holds more than ``3 x baseline + 5`` events (the baseline: a slow
   average of the bins' counts), at least 200 ms after the previous onset;
2. features: how many times each channel fired in the 30 ms after the onset, scaled to unit
   length;
3. decision: the stimulus whose template (the average features of the stimuli already seen)
   is nearest (largest dot product, sent as the confidence); then, if a ground-truth MARKER
   says a stimulus started up to 50 ms before, that stimulus's template learns the
   features (it learns from the past only: each decision is made before its own label is
   looked at). Onsets before any template exists get no answer.

    python examples/dut_threshold.py --port /dev/ttyUSB0          # serial (or a pty)
    python examples/dut_threshold.py --can can0 [--fd] [--board-id N]
"""

from __future__ import annotations

import argparse
from collections import deque

import numpy as np

import protocols

BIN_US, WINDOW_US, REFRACTORY_US = 5_000, 30_000, 200_000


class ThresholdDut:
    """Onset by an activity threshold, nearest-template decision (see the module rule)."""

    def __init__(self, n_channels: int) -> None:
        self.n_channels = n_channels
        self.bin = -1  # the 5 ms bin being filled (board time // BIN_US)
        self.bin_addrs: list[int] = []  # its events' channels
        self.baseline = 0.0  # average events per bin, outside stimuli
        self.last_onset = -REFRACTORY_US
        self.window: np.ndarray | None = None  # channel counts since the current onset
        self.onset_us = 0
        self.sums: dict[int, np.ndarray] = {}  # stimulus id -> summed unit features
        self.truth: deque[tuple[int, int]] = deque(maxlen=16)  # (onset µs, stimulus id)

    def marker(self, m: protocols.Marker) -> None:
        if m.phase == protocols.MarkerPhase.ONSET:
            self.truth.append((m.t_us, m.stimulus_id))

    def events(self, t_us: np.ndarray, addr: np.ndarray) -> list[tuple[int, float]]:
        """Feed events in time order; return the decisions made: (stimulus id, confidence)."""
        out = []
        for t, a in zip(t_us.tolist(), addr.tolist(), strict=True):
            if self.bin < 0:
                self.bin = t // BIN_US
            while t // BIN_US > self.bin:  # close the bins before this event
                out += self._close_bin()
            self.bin_addrs.append(a)
            if self.window is not None:
                self.window[a] += 1
        return out

    def _close_bin(self) -> list[tuple[int, float]]:
        start, n = self.bin * BIN_US, len(self.bin_addrs)
        out = []
        if self.window is not None and start + BIN_US >= self.onset_us + WINDOW_US:
            out = self._decide()
        elif (self.window is None and start - self.last_onset >= REFRACTORY_US
              and n > 3 * self.baseline + 5):
            self.last_onset = self.onset_us = start
            self.window = np.bincount(self.bin_addrs, minlength=self.n_channels).astype(float)
        elif self.window is None:
            self.baseline += 0.02 * (n - self.baseline)
        self.bin += 1
        self.bin_addrs = []
        return out

    def _decide(self) -> list[tuple[int, float]]:
        assert self.window is not None
        x = self.window / max(float(np.linalg.norm(self.window)), 1e-9)
        self.window = None
        out = []
        if self.sums:
            ids = list(self.sums)
            scores = [float(x @ (s / np.linalg.norm(s))) for s in self.sums.values()]
            best = int(np.argmax(scores))
            out.append((ids[best], min(max(scores[best], 0.0), 1.0)))
        # learn from a true onset only: a marker at most 50 ms before the onset bin's end
        true = [sid for t, sid in self.truth if 0 <= self.onset_us + BIN_US - t <= 50_000]
        if true:
            self.sums[true[-1]] = self.sums.get(true[-1], np.zeros_like(x)) + x
        return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    link = ap.add_mutually_exclusive_group(required=True)
    link.add_argument("--port", help="serial port (or pty) the board streams on")
    link.add_argument("--can", metavar="CHANNEL", help="CAN channel, e.g. can0 or vcan0")
    ap.add_argument("--baud", type=int, default=921_600)
    ap.add_argument("--interface", default="socketcan", help="python-can interface")
    ap.add_argument("--fd", action="store_true", help="the board sends CAN FD")
    ap.add_argument("--board-id", type=int, default=0)
    ap.add_argument("--channels", type=int, default=protocols.N_CHANNELS)
    args = ap.parse_args()

    if args.port:
        import serial

        port = serial.Serial(args.port, args.baud, timeout=0.05)
        decoder, encoder = protocols.SerialDecoder(), protocols.SerialEncoder()
        read = lambda: port.read(65536)  # noqa: E731
        send = port.write
    else:
        import can

        bus = can.Bus(channel=args.can, interface=args.interface, fd=args.fd)
        decoder = protocols.CanDecoder(board_id=args.board_id, fd=args.fd)
        encoder = protocols.CanEncoder(board_id=args.board_id, fd=args.fd)

        def read() -> list[protocols.CanFrame]:
            msg = bus.recv(0.05)
            return [] if msg is None else [protocols.CanFrame(
                msg.arbitration_id, bytes(msg.data), bool(msg.is_fd))]

        def send(frames: list[protocols.CanFrame]) -> None:
            for f in frames:
                bus.send(can.Message(arbitration_id=f.arbitration_id, data=f.data,
                                     is_fd=f.is_fd, bitrate_switch=False,
                                     is_extended_id=False))

    dut, token = ThresholdDut(args.channels), 0
    try:
        while True:
            res = decoder.feed(read())
            for rec in res.records:
                if isinstance(rec, protocols.Marker):
                    dut.marker(rec)
                elif isinstance(rec, protocols.RunEnd):  # the board's run is over
                    return
            for stimulus_id, confidence in dut.events(res.events["t"], res.events["addr"]):
                token = (token + 1) % 65536
                send(encoder.command(protocols.Decision(token, stimulus_id, confidence)))
                print(f"decided stimulus {stimulus_id} (confidence {confidence:.2f})",
                      flush=True)
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
