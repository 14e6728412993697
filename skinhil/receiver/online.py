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
"""Most steps the receiver processes in one block (0.1 s at 0.1 ms). A backlog (a receiver
that fell behind) is processed block by block, so memory stays bounded whatever the jump:
only the PSP of decision windows is ever written (see :class:`OnsetWindows`), but a block's
population counts and the arrays of its events grow with its length
(``benchmarks/bench_receiver_backlog.py``: inside user-mode Linux every fresh page is a round
trip to the host)."""


@dataclass
class _OpenWindow:
    """A window being filled: onset at ``detect_step``, rows from ``start_step``; ``psp`` its
    PSP rows (the steps the filter has passed are written, zero before the stream began)."""

    detect_step: int
    start_step: int
    psp: np.ndarray


class OnsetWindows:
    """Events on board time → PSP bank and onset detector → decision windows (no decoder).

    The PSP filter runs ``lookback_steps`` behind the onset detector (its state at step
    :attr:`filtered_step`, the events since then kept), and writes its values only into open
    windows: so the per-step cost is the decay of its states, and a window starting up to
    ``lookback_steps`` before the onset that opened it still gets every row. A window whose
    last step the detector passed is finished on a copy of the filter over the events kept.
    The values are those of the dense filter (:meth:`PSPFilterBank.step_block` over per-step
    counts) to the bit, whatever the chunks the events came in.
    """

    def __init__(self, dt_s: float, n_channels: int, psp_params: PSPParams,
                 window_steps: int, onset: OnsetParams | None = None) -> None:
        self.dt_s = float(dt_s)
        self.dt_us = step_us(self.dt_s)
        self.n_channels = int(n_channels)
        self.bank = PSPFilterBank(self.n_channels, self.dt_s, psp_params)
        self.detector = OnsetDetector(self.dt_s, onset)
        self.window_steps = int(window_steps)
        self.lookback_steps = int(round(self.detector.params.lookback_s / self.dt_s))
        empty = np.zeros(0, np.int64)
        self.bank.copy().step_events(1, empty, empty)  # the kernel loaded before the stream
        self.reset()

    def reset(self) -> None:
        """Back to board time 0 with empty filters and no open window."""
        self.bank.reset()
        self.detector.reset()
        self.next_step = 0
        self.filtered_step = 0
        """Steps before this one are in the PSP filter's state."""
        self._pending: list[np.ndarray] = []
        self._kept_steps = np.zeros(0, np.int64)
        self._kept_addrs = np.zeros(0, np.int64)
        """Events of the steps from :attr:`filtered_step` on (absolute steps, ascending)."""
        self._open: list[_OpenWindow] = []
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

    def _take_events(self, end_step: int) -> tuple[np.ndarray, np.ndarray]:
        """The queued events of the steps before ``end_step`` as (absolute step, channel),
        by step; late ones (for steps already processed) counted and applied at the current
        step, bad addresses counted and dropped."""
        if not self._pending:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        ev = np.concatenate(self._pending) if len(self._pending) > 1 else self._pending[0]
        steps = ev["t"] // self.dt_us
        later = steps >= end_step
        if later.any():
            self._pending = [ev[later]]
            ev, steps = ev[~later], steps[~later]
        else:
            self._pending = []
        late = steps < self.next_step
        if late.any():
            self.late_events += int(late.sum())
            self.max_late_us = max(self.max_late_us,
                                   int(self.next_step - steps.min()) * self.dt_us)
            steps = np.maximum(steps, self.next_step)
        addr = ev["addr"].astype(np.int64)
        bad = addr >= self.n_channels
        if bad.any():
            self.bad_address_events += int(bad.sum())
            steps, addr = steps[~bad], addr[~bad]
        if steps.size > 1 and np.any(steps[1:] < steps[:-1]):
            order = np.argsort(steps, kind="stable")
            steps, addr = steps[order], addr[order]
        return steps.astype(np.int64), addr

    def _advance_steps(self, end_step: int) -> list[Window]:
        n = end_step - self.next_step
        if n <= 0:
            return []
        first = self.next_step
        steps, addr = self._take_events(end_step)
        counts = np.bincount(steps - first, minlength=n).astype(np.float64)
        onsets = self.detector.process(counts)
        self.next_step = end_step
        for d in onsets:
            a = d - self.lookback_steps
            self._open.append(_OpenWindow(d, a, np.zeros((self.window_steps,
                                                          self.n_channels))))
        self._kept_steps = np.concatenate([self._kept_steps, steps])
        self._kept_addrs = np.concatenate([self._kept_addrs, addr])
        self._filter(self.bank, self.filtered_step, max(self.filtered_step,
                                                          end_step - self.lookback_steps),
                     self._open)
        self.filtered_step = max(self.filtered_step, end_step - self.lookback_steps)
        keep = np.searchsorted(self._kept_steps, self.filtered_step)
        self._kept_steps, self._kept_addrs = self._kept_steps[keep:], self._kept_addrs[keep:]
        return self._ready()

    def _filter(self, bank: PSPFilterBank, lo: int, hi: int,
                windows: list[_OpenWindow]) -> None:
        """Step ``bank`` from step ``lo`` to ``hi`` over the kept events, writing the rows of
        ``windows`` that fall in between."""
        if hi <= lo:
            return
        i0, i1 = np.searchsorted(self._kept_steps, [lo, hi])
        steps, addr = self._kept_steps[i0:i1] - lo, self._kept_addrs[i0:i1]
        cuts = sorted({lo, hi} | {min(max(b, lo), hi) for w in windows
                                  for b in (w.start_step, w.start_step + self.window_steps)})
        for a, b in zip(cuts[:-1], cuts[1:], strict=False):
            if b <= a:
                continue
            inside = [w for w in windows if w.start_step <= a
                      and b <= w.start_step + self.window_steps]
            j0, j1 = np.searchsorted(steps, [a - lo, b - lo])
            out = inside[0].psp if inside else None
            row = 0 if not inside else a - inside[0].start_step
            bank.step_events(b - a, steps[j0:j1] - (a - lo), addr[j0:j1],
                             None if out is None else out[row:row + b - a])
            for w in inside[1:]:
                r = a - w.start_step
                w.psp[r:r + b - a] = out[row:row + b - a]  # type: ignore[index]

    def _ready(self) -> list[Window]:
        out = []
        still = []
        for w in self._open:
            end = w.start_step + self.window_steps
            if end > self.next_step:
                still.append(w)
                continue
            if end > self.filtered_step:  # its last rows: on a copy, from the events kept
                self._filter(self.bank.copy(), self.filtered_step, end, [w])
            out.append(Window(w.detect_step, w.start_step, w.psp))
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

