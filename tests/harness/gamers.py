"""Scripted decoders that read no spike (tests/test_suite_gamers.py): each is the commands
it sends, by the tick they arrive at (:data:`harness.suite_play.Script`), made without
looking at the stream: at a fixed cadence, in bursts, as spam, from another seed's truth."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

import protocols
from harness.suite_play import Script, tick_of
from skinhil.tasks import registry

Values = Callable[[np.random.Generator, int], tuple[float, ...]]
"""The values of the ``i``-th answer (a generator for the gamers that draw)."""


class Tokens:
    """Command tokens, one count per gamer (16 bits, wrapping)."""

    def __init__(self) -> None:
        self.n = 0

    def next(self) -> int:
        self.n = (self.n + 1) % 65536
        return self.n


def command(task: int, token: int, values: tuple[float, ...]) -> Any:
    """An ANSWER of ``task`` (a DECISION for classification: the same score, SPEC §3.5.3)."""
    if task == protocols.Task.CLASSIFICATION:
        return protocols.Decision(token, int(values[0]))
    return protocols.Answer(token, protocols.Task(task), values)


def cadence(task: int, values: Values, period_s: float, duration_s: float,
            per_beat: int = 1, seed: int = 0) -> Script:
    """``per_beat`` answers of ``task`` every ``period_s`` (s) from board time 0 to
    ``duration_s``; the ``j``-th answer's values ``values(rng, j)``."""
    rng = np.random.default_rng(seed)
    tokens = Tokens()
    out: Script = {}
    j = 0
    for beat in range(int(duration_s / period_s) + 1):
        for _ in range(per_beat):
            out.setdefault(tick_of(beat * period_s), []).append(
                command(task, tokens.next(), values(rng, j)))
            j += 1
    return out


def constant(v: Sequence[float]) -> Values:
    """The same values every time."""
    return lambda rng, j: tuple(float(x) for x in v)


def cycle(values: Sequence[Sequence[float]]) -> Values:
    """``values`` in turn."""
    return lambda rng, j: tuple(float(x) for x in values[j % len(values)])


def uniform(lo: Sequence[float], hi: Sequence[float]) -> Values:
    """Drawn uniformly in the box ``lo``..``hi``."""
    return lambda rng, j: tuple(float(x) for x in rng.uniform(lo, hi))


def choice(classes: Sequence[float]) -> Values:
    """Drawn uniformly from ``classes``."""
    return lambda rng, j: (float(classes[int(rng.integers(len(classes)))]),)


def replay_markers(truth: str, delay_s: float) -> Script:
    """A DECISION naming each onset marker's stimulus of another run's truth file, at its
    time plus ``delay_s`` (s): the classification of another seed replayed."""
    tokens = Tokens()
    out: Script = {}
    for line in truth.splitlines():
        row = json.loads(line)
        if row.get("type") == "marker" and row.get("phase") == "onset":
            k = tick_of(row["t_us"] * 1e-6 + delay_s)
            out.setdefault(k, []).append(protocols.Decision(tokens.next(),
                                                            int(row["stimulus_id"])))
    return out


def task_id(name: str) -> int:
    """The wire id of task ``name``."""
    return registry.by_name(name).wire_id


GRIP_STEP_N = 0.09
"""The most a scripted grip moves per tick (N): within the board's rate bound (100 N/s at
1 ms ticks, docs/grasp.md), so no GRIP is refused."""


def grips(targets: Sequence[tuple[float, float]], duration_s: float,
          start_n: float = 0.3) -> Script:
    """GRIPs that follow ``targets`` ((board time s, grip N) in time order: the grip wanted
    from that time on) from the hand's ``start_n``, moving at most :data:`GRIP_STEP_N` per
    tick, one GRIP per tick while it moves."""
    tokens = Tokens()
    out: Script = {}
    grip = start_n
    wanted = list(targets)
    target = start_n
    for k in range(1, tick_of(duration_s)):
        while wanted and tick_of(wanted[0][0]) <= k:
            target = wanted.pop(0)[1]
        if abs(target - grip) < 1e-9:
            continue
        grip = round(grip + max(-GRIP_STEP_N, min(GRIP_STEP_N, target - grip)), 6)
        out[k] = [protocols.Command(tokens.next(), protocols.CommandCode.GRIP, grip)]
    return out


def held_at(grip_n: float, duration_s: float) -> Script:
    """A constant grip of ``grip_n`` (N) from the start."""
    return grips([(0.0, grip_n)], duration_s)


def dither(low_n: float, high_n: float, period_s: float, duration_s: float) -> Script:
    """A blind triangle between ``low_n`` and ``high_n`` (N), ``period_s`` (s) a cycle."""
    half = period_s / 2
    return grips([(i * half, high_n if i % 2 == 0 else low_n)
                  for i in range(int(duration_s / half) + 1)], duration_s)
