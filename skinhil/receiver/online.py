"""The online classifier: events on board time → PSP filter bank → onset → window decision.

Per processed block of simulation steps (board time ``k·dt``, exact from the events'
microsecond timestamps):

1. the events of the block become per-step spike counts (n_steps, n_channels);
2. the PSP filter bank steps through them (:meth:`skinhil.PSPFilterBank.step_block`), so its
   state is the exact eq. 12 filter of every spike received so far;
3. the onset detector (:class:`~skinhil.receiver.onset.OnsetDetector`) sees the population
   counts and reports onset steps;
4. for an onset detected at step ``d`` the decision window starts at ``a = d − lookback``
   and spans the decoder's feature window; once board time passes its end, its PSP values
   go through the decoder's own feature code and linear classifier: the same features as
   in training, where the window starts at the true onset.

Nothing here reads the ground-truth markers; :mod:`skinhil.receiver.scoring` does.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from skinhil.errors import ConfigError, ModelFileError
from skinhil.psp import PSPFilterBank
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


class OnlineClassifier:
    """Steps the PSP filter bank and the onset detector on board time; decides windows."""

    def __init__(self, decoder: WindowDecoder, onset: OnsetParams | None = None) -> None:
        self.decoder = decoder
        self.dt_s = decoder.dt_s
        self.dt_us = int(round(self.dt_s * 1e6))
        if self.dt_us <= 0 or abs(self.dt_us - self.dt_s * 1e6) > 1e-6:
            raise ModelFileError(f"decoder step {self.dt_s!r} s is not a whole number of µs; "
                                 "retrain it with a step such as 1e-4 s")
        self.n_channels = decoder.n_channels
        self.bank = PSPFilterBank(self.n_channels, self.dt_s, decoder.psp_params)
        self.detector = OnsetDetector(self.dt_s, onset)
        self.window_steps = decoder.window_steps
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
        self.bad_address_events = 0

    @property
    def board_time_us(self) -> int:
        """Board time (µs) up to which every step has been processed."""
        return self.next_step * self.dt_us

    def push(self, events: np.ndarray) -> None:
        """Queue received events (EVENT_DTYPE); they are applied when their step is processed."""
        if events.shape[0]:
            self._pending.append(events)

    def advance(self, t_us: int) -> list[Prediction]:
        """Process every step that starts before board time ``t_us`` (µs); return decisions."""
        end_step = int(t_us // self.dt_us)
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
        return self._decide_ready()

    def _keep_history(self, psp: np.ndarray, first: int) -> None:
        joined = np.concatenate([self._history, psp]) if self._history.shape[0] else psp
        start = first - self._history.shape[0]
        keep_from = self.next_step - self.history_steps
        if self._open:
            keep_from = min(keep_from, min(a for _, a in self._open))
        cut = max(0, keep_from - start)
        self._history = joined[cut:]
        self._history_start = start + cut

    def _decide_ready(self) -> list[Prediction]:
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
            label, scores = self.decoder.decide(window)
            out.append(Prediction(detect_t_us=d * self.dt_us, window_t_us=a * self.dt_us,
                                  decided_t_us=(a + self.window_steps) * self.dt_us,
                                  label=label, scores=tuple(float(s) for s in scores),
                                  host_time_s=time.monotonic()))
        self._open = still
        return out


def check_channels(decoder: WindowDecoder, n_channels: int) -> None:
    """Refuse a decoder trained for another channel count than the stream's."""
    if decoder.n_channels != n_channels:
        raise ConfigError(f"the model expects {decoder.n_channels} channels but the stream has "
                          f"{n_channels}; use a model trained for this board")
