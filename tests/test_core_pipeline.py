"""SensorPipeline: the mechanics and the neurons on two threads give the same spikes as one
thread, block for block, two calls late."""

import numpy as np
import pytest

from skinhil import SkinModel, SkinParams
from skinhil.model.pipeline import SensorPipeline
from skinhil.model.sensor import SkinSensor
from skinhil.model.timeline import Timeline

DT_S = 1e-4


@pytest.mark.parametrize("size", [(6, 6), (16, 16)])  # modal and leapfrog mechanics
def test_pipeline_gives_the_same_spikes_two_blocks_late(size: tuple[int, int]) -> None:
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
            assert pipe.in_flight == pipe.sensor.step_index - pipe.spike_index
            if i < 2:
                assert spikes.shape == (0, model.n_springs) and first == 0
            else:
                got.append(spikes)
                firsts.append(first)
            # a change of noise reaches the next block whose neurons start: in the pipeline
            # the block after the next call's, so the same change is made one call later
            if i == 60:
                one.set_snr(20.0)
            if i == 61:
                pipe.set_snr(20.0)
        spikes, first = pipe.flush()
        assert first == sum(blocks[:-2]) and len(spikes) == sum(blocks[-2:])
        got.extend(np.split(spikes, [blocks[-2]]))
        firsts.extend([first, first + blocks[-2]])
        assert pipe.in_flight == 0 and pipe.spike_index == one.step_index
        assert firsts == list(np.cumsum([0] + blocks[:-1]))
        for exp, out in zip(expected, got, strict=True):
            assert np.array_equal(exp, out)
        assert sum(int(s.sum()) for s in got) > 0
        pipe.reset()
        assert pipe.spike_index == pipe.sensor.step_index == pipe.in_flight == 0
        assert pipe.advance(timeline.forces(np.arange(10) * DT_S))[0].shape[0] == 0
        assert pipe.in_flight == 10
    finally:
        pipe.close()
