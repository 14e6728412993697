"""PSP traces of chosen sensors (the live view's and the LSL outlet's): the eq. 12 filter of
the events binned at 1 kHz, handed out in chunks, whatever the reads the events came in."""

from __future__ import annotations

import numpy as np
import pytest

from skinhil.errors import ConfigError
from skinhil.events import EVENT_DTYPE
from skinhil.model.psp import PSPFilterBank
from skinhil.receiver.traces import PspTraces


def _events(rng: np.random.Generator, n: int, channels: int, span_us: int) -> np.ndarray:
    ev = np.zeros(n, dtype=EVENT_DTYPE)
    ev["t"] = np.sort(rng.integers(0, span_us // 100, n)) * 100 + 5_000_000
    ev["addr"] = rng.integers(0, channels, n)
    ev["p"] = 1
    return ev


def test_traces_equal_the_filter_of_the_binned_events_in_any_reads() -> None:
    rng = np.random.default_rng(3)
    ev = _events(rng, 4000, 40, 2_000_000)
    chosen = [3, 17, 39]
    traces = PspTraces(chosen, 40)
    got, firsts = [], []
    for part in np.array_split(ev, 137):  # reads of uneven sizes
        traces.add(part)
        first, values = traces.advance(int(part["t"][-1]) if part.size else 0)
        assert values.shape[0] == 0 or values.shape[0] >= traces.chunk_samples
        if values.shape[0]:
            firsts.append(first)
            got.append(values)
    first, values = traces.advance(int(ev["t"][-1]) + 1000, final=True)
    got.append(values)
    out = np.concatenate(got)
    assert firsts[0] == 5000 and first == firsts[0] + sum(g.shape[0] for g in got[:-1])
    bins = ev["t"] // 1000 - 5000
    counts = np.zeros((int(bins.max()) + 1, 3))
    for k, c in enumerate(chosen):
        np.add.at(counts[:, k], bins[ev["addr"] == c], 1)
    want = PSPFilterBank(3, 1e-3).filter(counts)
    assert out.shape == want.shape
    np.testing.assert_allclose(out, want, rtol=1e-5, atol=1e-6)


def test_traces_refuse_sensors_the_skin_lacks() -> None:
    with pytest.raises(ConfigError, match="0..9"):
        PspTraces([0, 10], 10)
    with pytest.raises(ConfigError, match="repeat"):
        PspTraces([2, 2], 10)
