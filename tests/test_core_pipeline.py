"""SensorPipeline: the mechanics and the neurons on two threads give the same spikes as one
thread, block for block, one call late."""

import numpy as np
import pytest

from skinhil import SkinModel, SkinParams
from skinhil.pipeline import SensorPipeline
from skinhil.sensor import SkinSensor
from skinhil.timeline import Timeline

DT_S = 1e-4


@pytest.mark.parametrize("size", [(6, 6), (16, 16)])  # modal and leapfrog mechanics
def test_pipeline_gives_the_same_spikes_one_block_late(size: tuple[int, int]) -> None:
    model = SkinModel(SkinParams(size=size))
    timeline = Timeline(DT_S, seed=3, size=size)
    one = SkinSensor(model, DT_S, snr_db=10.0, seed=7)
    pipe = SensorPipeline(SkinSensor(model, DT_S, snr_db=10.0, seed=7))
    blocks = [10] * 120 + [3, 0, 17] + [10] * 30
    try:
        expected: list[np.ndarray] = []
        got: list[np.ndarray] = []
        firsts: list[int] = []
        for i, n in enumerate(blocks):
            forces = timeline.forces((one.step_index + np.arange(n)) * DT_S)
            expected.append(one.advance(forces)[1])
            spikes, first = pipe.advance(forces)
            assert pipe.sensor.step_index == one.step_index
            assert pipe.spike_index == first + len(spikes)
            assert pipe.in_flight == n
            if i == 0:
                assert spikes.shape == (0, model.n_springs) and first == 0
            else:
                got.append(spikes)
                firsts.append(first)
            # a change of noise reaches the neurons' next block: in the pipeline that is the
            # block in flight, so the same change comes one call later
            if i == 60:
                one.set_snr(20.0)
            if i == 61:
                pipe.sensor.set_snr(20.0)
        spikes, first = pipe.flush()
        got.append(spikes)
        firsts.append(first)
        assert pipe.in_flight == 0 and pipe.spike_index == one.step_index
        assert firsts == list(np.cumsum([0] + blocks[:-1]))
        for exp, out in zip(expected, got, strict=True):
            assert np.array_equal(exp, out)
        assert sum(int(s.sum()) for s in got) > 0
        pipe.reset()
        assert pipe.spike_index == pipe.sensor.step_index == pipe.in_flight == 0
        assert pipe.advance(timeline.forces(np.arange(10) * DT_S))[0].shape[0] == 0
    finally:
        pipe.close()
