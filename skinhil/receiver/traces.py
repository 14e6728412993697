"""PSP traces of chosen sensors at a regular rate, from the events of the stream.

The live view and the LSL outlet both show the eq. 12 PSP of some sensors as a regular
signal (1 kHz by default). :class:`PspTraces` bins the events it is given into samples of
``1/rate_hz`` s of board time and steps a :class:`skinhil.model.psp.PSPFilterBank` of the
chosen channels through the bin counts: a spike counts at the start of its bin (at 1 kHz it
is placed up to 1 ms early, within a sixth of the kernel's rise), O(channels) per sample.
It is not the classifier's filter (that one runs at the simulation step): it is a display
and export signal.

Samples are handed out only for bins board time has passed (``advance``): the stream is
in time order, so a bin before the newest event's time is complete, and so is one before a
STATUS sent with no event queued (:func:`skinhil.receiver.in_stream_order`): a quiet board's
traces go on. The traces start at the first event or advance, whichever comes first. They
are handed out in chunks of at least ``chunk_samples`` (20 ms of board time by default,
unless ``final``): a listener called for every small read of the link then filters and
publishes 50 times a second, not a thousand.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skinhil.errors import ConfigError
from skinhil.model.psp import PSPFilterBank

TRACE_RATE_HZ = 1000.0
"""Samples per second of board time of the PSP traces."""

CHUNK_SAMPLES = 20
"""Fewest samples :meth:`PspTraces.advance` hands out at once (20 ms at 1 kHz)."""

MAX_SAMPLES_PER_ADVANCE = 10_000
"""Most samples one :meth:`PspTraces.advance` returns (10 s at 1 kHz); a longer jump (a
stream that resumes after a long pause) restarts the traces at the new time."""


class PspTraces:
    """Events → PSP (dimensionless; the kernel peaks at ≈1 per spike) of ``channels`` at
    ``rate_hz`` samples per second of board time."""

    def __init__(self, channels: Sequence[int], n_channels: int,
                 rate_hz: float = TRACE_RATE_HZ, chunk_samples: int = CHUNK_SAMPLES) -> None:
        chans = np.asarray(list(channels), dtype=np.int64)
        if chans.size == 0 or chans.min() < 0 or chans.max() >= n_channels:
            raise ConfigError(f"PSP sensors must be addresses 0..{n_channels - 1}, got "
                              f"{list(channels)[:8]!r} — give sensors such as 0,17,42")
        if len(set(chans.tolist())) != chans.size:
            raise ConfigError("PSP sensors repeat an address — give each sensor once")
        self.channels = chans
        self.rate_hz = float(rate_hz)
        self.chunk_samples = int(chunk_samples)
        self.sample_us = int(round(1e6 / self.rate_hz))
        self.bank = PSPFilterBank(int(chans.size), self.sample_us * 1e-6)
        self._column = np.full(int(n_channels), -1, dtype=np.int64)
        self._column[chans] = np.arange(chans.size)
        self.next_sample = -1
        """Index of the next sample to hand out (sample k covers board time k·sample_us µs
        onward); -1 before the first event or :meth:`advance`."""
        self._pending: list[np.ndarray] = []

    def add(self, events: np.ndarray) -> None:
        """Events (EVENT_DTYPE, board time ``t`` in µs) just received."""
        if events.shape[0] == 0:
            return
        col = self._column[events["addr"].astype(np.int64)]
        keep = col >= 0
        if self.next_sample < 0:
            self.next_sample = int(events["t"][0]) // self.sample_us
        if keep.any():
            pending = np.empty((int(keep.sum()), 2), dtype=np.int64)
            pending[:, 0] = events["t"][keep] // self.sample_us
            pending[:, 1] = col[keep]
            self._pending.append(pending)

    def advance(self, board_t_us: int, final: bool = False) -> tuple[int, np.ndarray]:
        """Samples of every bin that ends by board time ``board_t_us`` (µs), once there are
        ``chunk_samples`` of them or ``final``: (index of the first sample, values of shape
        (n_samples, n_chosen), float32)."""
        end = int(board_t_us) // self.sample_us
        if self.next_sample < 0:  # time known before any event (a STATUS): start there
            self.next_sample = end
        first = self.next_sample
        if (end - first < self.chunk_samples and not final):
            return max(first, 0), np.zeros((0, self.channels.size), dtype=np.float32)
        if end - first > MAX_SAMPLES_PER_ADVANCE:
            self.bank.reset()
            first = end - MAX_SAMPLES_PER_ADVANCE
        n = max(0, end - first)
        counts = np.zeros((n, self.channels.size))
        if self._pending:
            pending = np.concatenate(self._pending)
            now = (pending[:, 0] >= first) & (pending[:, 0] < end)
            np.add.at(counts, (pending[now, 0] - first, pending[now, 1]), 1.0)
            later = pending[pending[:, 0] >= end]
            self._pending = [later] if later.shape[0] else []
        self.next_sample = max(self.next_sample, end)
        if n == 0:
            return first, np.zeros((0, self.channels.size), dtype=np.float32)
        return first, self.bank.step_block(counts).astype(np.float32)
