"""The online classifier: events on board time → PSP filter bank → onset → window decision.

Two stages, so offline training and the live receiver cut their windows with the same code:

:class:`OnsetWindows` (no decoder), per processed block of simulation steps (board time
``k·dt``, exact from the events' microsecond timestamps):

1. the events of the block become per-step spike counts (n_steps, n_channels);
2. the PSP filter bank steps through them (:meth:`skinhil.PSPFilterBank.step_block`), so its
   state is the exact eq. 12 filter of every spike received so far — including the tails of
   earlier stimuli, as on the board;
3. the onset detector (:class:`~skinhil.receiver.onset.OnsetDetector`) sees the population
   counts and reports onset steps;
4. for an onset detected at step ``d`` the window starts at ``a = d − lookback`` and spans
   ``window_steps``; once board time passes its end, its PSP values (window_steps,
   n_channels) are handed out as a :class:`Window`.

:class:`OnlineClassifier` puts each window through the decoder's own feature code and linear
classifier (:class:`~skinhil.receiver.decoder_adapter.WindowDecoder`). Training
(:mod:`skinhil.receiver.training`) runs :class:`OnsetWindows` on a simulated board stream,
so the decoder is fitted on exactly the windows it later decides online.

Nothing here reads the ground-truth markers; :mod:`skinhil.receiver.scoring` does.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from skinhil.errors import ModelFileError
from skinhil.model.psp import PSPFilterBank, PSPParams
from skinhil.receiver.decoder_adapter import WindowDecoder
from skinhil.receiver.onset import OnsetDetector
from skinhil.receiver.params import OnsetParams


@dataclass(frozen=True)
class Prediction:
    """One decision of the online classifier.

    Board times in µs: ``detect_t_us`` the step the onset was detected at, ``window_t_us``
    the start of the decision window, ``decided_t_us`` its end (the board time the decision
    needed). ``label`` is the predicted class (stimulus id), ``scores`` the decoder's
    decision values per class, ``host_time_s`` the host monotonic time (s) of the decision.
    """

    detect_t_us: int
    window_t_us: int
    decided_t_us: int
    label: int
    scores: tuple[float, ...]
    host_time_s: float


@dataclass(frozen=True)
class Window:
    """A decision window: onset detected at step ``detect_step``, window from ``start_step``
    (absolute steps since the stream began), ``psp`` its PSP values (window_steps,
    n_channels), zero before the stream began."""

    detect_step: int
    start_step: int
    psp: np.ndarray


def step_us(dt_s: float) -> int:
    """The step ``dt_s`` (s) in whole µs; refuses steps that are not."""
    dt_us = int(round(dt_s * 1e6))
    if dt_us <= 0 or abs(dt_us - dt_s * 1e6) > 1e-6:
        raise ModelFileError(f"step {dt_s!r} s is not a whole number of µs; use a step such as "
                             "1e-4 s")
    return dt_us


MAX_BLOCK_STEPS = 1_000
"""Most steps the receiver filters in one block (0.1 s at 0.1 ms: 2.7 MB of PSP values for
338 channels). A backlog (a receiver that fell behind) is filtered block by block, and
blocks this small reuse the memory the last one freed: 1 s blocks (27 MB) took fresh pages
every time, 21,000 page faults per 12 s of stream on the host and 284,000 inside user-mode
Linux, where each is a round trip to the host: 1.24 s per 1 s of stream, so a receiver
that once fell behind never caught up (its next backlog larger). In blocks of 1,000 steps:
0.02-0.03 s per 1 s of stream inside user-mode Linux at any backlog, 1,000-2,000 faults
(``benchmarks/bench_receiver_backlog.py``)."""


class OnsetWindows:
    """Events on board time → PSP bank and onset detector → decision windows (no decoder)."""

    def __init__(self, dt_s: float, n_channels: int, psp_params: PSPParams,
                 window_steps: int, onset: OnsetParams | None = None) -> None:
        self.dt_s = float(dt_s)
        self.dt_us = step_us(self.dt_s)
        self.n_channels = int(n_channels)
        self.bank = PSPFilterBank(self.n_channels, self.dt_s, psp_params)
        self.detector = OnsetDetector(self.dt_s, onset)
        self.window_steps = int(window_steps)
        self.lookback_steps = int(round(self.detector.params.lookback_s / self.dt_s))
        self.history_steps = self.lookback_steps + self.window_steps
        self.reset()

    def reset(self) -> None:
        """Back to board time 0 with empty filters and no open window."""
        self.bank.reset()
        self.detector.reset()
        self.next_step = 0
        self._pending: list[np.ndarray] = []
        self._history = np.zeros((0, self.n_channels))
        self._history_start = 0
        self._open: list[tuple[int, int]] = []  # (detect step, window start step)
        self.late_events = 0
        self.max_late_us = 0
        """Largest lateness (µs) of an event for an already processed step."""
        self.bad_address_events = 0

    @property
    def board_time_us(self) -> int:
        """Board time (µs) up to which every step has been processed."""
        return self.next_step * self.dt_us

    def push(self, events: np.ndarray) -> None:
        """Queue received events (EVENT_DTYPE); they are applied when their step is processed."""
        if events.shape[0]:
            self._pending.append(events)

    def advance(self, t_us: int) -> list[Window]:
        """Process every step that starts before board time ``t_us`` (µs); return the windows
        that became complete.

        A long jump (the host clock's estimate running ahead of a board that lags, or a long
        silence) is processed in blocks of at most ``MAX_BLOCK_STEPS``, so memory stays
        bounded whatever the jump.
        """
        end_step = int(t_us // self.dt_us)
        out: list[Window] = []
        while end_step - self.next_step > MAX_BLOCK_STEPS:
            out += self._advance_steps(self.next_step + MAX_BLOCK_STEPS)
        return out + self._advance_steps(end_step)

    def _advance_steps(self, end_step: int) -> list[Window]:
        n = end_step - self.next_step
        if n <= 0:
            return []
        counts = np.zeros((n, self.n_channels))
        if self._pending:
            ev = np.concatenate(self._pending)
            steps = ev["t"] // self.dt_us
            later = steps >= end_step
            self._pending = [ev[later]] if later.any() else []
            now = ev[~later]
            rel = steps[~later] - self.next_step
            late = rel < 0
            if late.any():
                self.late_events += int(late.sum())
                self.max_late_us = max(self.max_late_us, int(-rel.min()) * self.dt_us)
                rel = np.maximum(rel, 0)
            addr = now["addr"].astype(np.int64)
            bad = addr >= self.n_channels
            if bad.any():
                self.bad_address_events += int(bad.sum())
            np.add.at(counts, (rel[~bad], addr[~bad]), 1.0)
        first = self.next_step
        psp = self.bank.step_block(counts)
        onsets = self.detector.process(counts.sum(axis=1))
        self.next_step = end_step
        for d in onsets:
            self._open.append((d, d - self.lookback_steps))
        self._keep_history(psp, first)
        return self._ready()

    def _keep_history(self, psp: np.ndarray, first: int) -> None:
        joined = np.concatenate([self._history, psp]) if self._history.shape[0] else psp
        start = first - self._history.shape[0]
        keep_from = self.next_step - self.history_steps
        if self._open:
            keep_from = min(keep_from, min(a for _, a in self._open))
        cut = max(0, keep_from - start)
        self._history = joined[cut:]
        self._history_start = start + cut

    def _ready(self) -> list[Window]:
        out = []
        still = []
        for d, a in self._open:
            if a + self.window_steps > self.next_step:
                still.append((d, a))
                continue
            lo = a - self._history_start
            window = self._history[max(lo, 0):lo + self.window_steps]
            if lo < 0:  # window starts before the stream did: zero PSP there
                window = np.concatenate([np.zeros((-lo, self.n_channels)), window])
            out.append(Window(d, a, window.copy()))
        self._open = still
        return out


class OnlineClassifier:
    """Decides every window of :class:`OnsetWindows` with a trained decoder."""

    def __init__(self, decoder: WindowDecoder, onset: OnsetParams | None = None) -> None:
        self.decoder = decoder
        self.windows = OnsetWindows(decoder.dt_s, decoder.n_channels, decoder.psp_params,
                                    decoder.window_steps, onset)
        self.dt_us = self.windows.dt_us

    def reset(self) -> None:
        """Back to board time 0 with empty filters and no open window."""
        self.windows.reset()

    @property
    def board_time_us(self) -> int:
        """Board time (µs) up to which every step has been processed."""
        return self.windows.board_time_us

    @property
    def late_events(self) -> int:
        """Events that arrived for steps already processed (applied at the current step)."""
        return self.windows.late_events

    def push(self, events: np.ndarray) -> None:
        """Queue received events (EVENT_DTYPE)."""
        self.windows.push(events)

    def advance(self, t_us: int) -> list[Prediction]:
        """Process every step that starts before board time ``t_us`` (µs); return decisions."""
        out = []
        for w in self.windows.advance(t_us):
            label, scores = self.decoder.decide(w.psp)
            out.append(Prediction(detect_t_us=w.detect_step * self.dt_us,
                                  window_t_us=w.start_step * self.dt_us,
                                  decided_t_us=(w.start_step + self.windows.window_steps)
                                  * self.dt_us,
                                  label=label, scores=tuple(float(s) for s in scores),
                                  host_time_s=time.monotonic()))
        return out

