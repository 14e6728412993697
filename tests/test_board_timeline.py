"""The board's timeline: seeded schedules, markers at the step where the force changes,
host stimuli, and a default schedule that stays short however long the board runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skinhil.model.stimuli import Schedule, ScheduledStimulus, direction_conditions
from skinhil.model.timeline import EXTEND_AHEAD_S, Timeline

DT_S = 1e-4
DT_US = 100


def _all_markers(tl: Timeline, until_s: float) -> list:
    out = []
    for t_us in range(0, int(until_s * 1e6) + 1, 50_000):
        tl.forces(np.array([t_us * 1e-6]))
        tl.prepare(t_us * 1e-6)
        out += tl.markers_before(t_us)
    return out


def test_default_schedule_is_seeded_and_its_markers_sit_on_steps() -> None:
    a = _all_markers(Timeline(DT_S, seed=3), 20.0)
    b = _all_markers(Timeline(DT_S, seed=3), 20.0)
    c = _all_markers(Timeline(DT_S, seed=4), 20.0)
    assert a == b and a != c
    assert [m.phase for m in a[:4]] == ["onset", "end", "onset", "end"]
    assert all(m.t_us % DT_US == 0 for m in a)
    assert all(0 <= m.stimulus_id <= 8 for m in a)
    assert [m.t_us for m in a] == sorted(m.t_us for m in a)
    # each ONSET is followed by the END of the same stimulus
    for on, end in zip(a[0::2], a[1::2], strict=False):
        assert on.phase == "onset" and end.phase == "end"
        assert on.stimulus_id == end.stimulus_id and end.t_us > on.t_us


def test_force_starts_at_the_onset_marker_step() -> None:
    tl = Timeline(DT_S, seed=0)
    onset = tl.markers_before(10**9)[0]
    assert onset.phase == "onset"
    k = onset.t_us // DT_US
    f = tl.forces((k - 1 + np.arange(3)) * DT_S)
    assert not np.any(f[0]) and np.any(f[1:])


def test_marker_times_round_up_to_the_next_step() -> None:
    stim = direction_conditions()[0]
    file = Schedule((ScheduledStimulus(0.01234, stim, 7),))
    tl = Timeline(DT_S, file, mode=Timeline.SCHEDULE_FILE)
    on, end = tl.markers_before(10**9)
    want = math.ceil((0.01234 + stim.onset_s) / DT_S - 1e-9) * DT_US
    assert (on.t_us, on.stimulus_id, on.phase) == (want, 7, "onset")
    assert end.t_us == math.ceil((0.01234 + stim.end_s) / DT_S - 1e-9) * DT_US


def test_host_stimulus_and_schedule_changes() -> None:
    tl = Timeline(DT_S, mode=Timeline.SCHEDULE_NONE)
    assert tl.markers_before(10**9) == []
    assert not np.any(tl.forces(np.arange(1000) * DT_S))
    assert tl.start_stimulus(4, 1.0)
    assert not tl.start_stimulus(999, 1.0)
    on, end = tl.markers_before(10**9)
    assert on.stimulus_id == 4 and on.t_us >= 1_000_000
    assert not tl.start_schedule(Timeline.SCHEDULE_FILE, 2.0)  # no file schedule
    assert not tl.start_schedule(7, 2.0)
    assert tl.start_schedule(Timeline.SCHEDULE_RANDOM, 2.0)
    assert all(m.t_us >= 2_000_000 for m in tl.markers_before(10**8))


def test_restarting_a_schedule_drops_the_future_stimuli_and_their_markers() -> None:
    tl = Timeline(DT_S, seed=1)
    assert tl.start_schedule(Timeline.SCHEDULE_NONE, 0.0)
    assert tl.markers_before(10**10) == []
    assert not np.any(tl.forces(np.arange(0, 100_000, 1000) * DT_S))


@pytest.mark.parametrize("hours", [1.0])
def test_a_long_run_keeps_the_schedule_short(hours: float) -> None:
    tl = Timeline(DT_S, seed=0)
    t_s = 0.0
    sizes = []
    while t_s < hours * 3600:
        tl.prepare(t_s)
        tl.forces(np.array([t_s]))
        sizes.append(len(tl.schedule.entries))
        t_s += 1.0
    # about two blocks of 64 stimuli at most, never an hour's worth
    assert max(sizes) <= 3 * 64
    assert tl.schedule.entries[-1].end_s > t_s + EXTEND_AHEAD_S - 1


def test_prepare_extends_before_forces_would_have_to() -> None:
    tl = Timeline(DT_S, seed=0)
    end0 = max(e.end_s for e in tl.schedule.entries)
    assert not tl.prepare(end0 - EXTEND_AHEAD_S - 1)
    assert tl.prepare(end0 - EXTEND_AHEAD_S + 1)
    assert max(e.end_s for e in tl.schedule.entries) > end0 + 10
