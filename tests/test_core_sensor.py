"""SkinSensor: its one-call compiled block equals the stepper and the neurons run in turn."""

import numpy as np

from skinhil import NeuronPopulation, SkinModel, Stimulus, paper_stimuli
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import Schedule, ScheduledStimulus

DT_S = 1e-4


def _overlapping_schedule() -> Schedule:
    poke = Stimulus("poke", {15: (0.1, -0.2, -0.3), 22: (0.0, 0.05, 0.0)}, onset_s=0.005,
                    indentation_s=0.04, decay_tau_s=0.02)
    a, _, c, _, e = paper_stimuli()
    return Schedule((ScheduledStimulus(0.01, a, 10), ScheduledStimulus(0.03, poke, 100),
                     ScheduledStimulus(0.05, e, 14), ScheduledStimulus(0.1, c, 12)))


def test_compiled_block_equals_stepper_then_neurons_at_10_db() -> None:
    """200 ms at 10 dB in the board's 1 ms blocks (and odd ones), with and without a
    schedule: same spring forces and spike for spike as the generic two-call path."""
    model = SkinModel()
    schedule = _overlapping_schedule()
    sensor = SkinSensor(model, DT_S, snr_db=10.0, seed=4)
    stepper = model.stepper(DT_S)
    neurons = NeuronPopulation(model.n_springs, snr_db=10.0, seed=4)
    blocks = [10] * 150 + [7, 1, 0, 32] + [10] * 46
    offset_s = 0.004
    for i, n in enumerate(blocks):
        t = (sensor.step_index + np.arange(n)) * DT_S - offset_s
        forces = schedule.force_at(t)
        if i % 2:
            springs, spikes = sensor.advance_schedule(schedule, n, t_offset_s=offset_s)
        else:
            springs, spikes = sensor.advance(forces)
        ref_springs = stepper.advance(forces)
        ref_spikes = neurons.step_block(ref_springs, DT_S)
        assert springs.shape == spikes.shape == (n, model.n_springs)
        assert np.array_equal(springs, ref_springs)
        assert np.array_equal(spikes, ref_spikes)
    assert sensor.step_index == sum(blocks)
    assert np.array_equal(sensor.neurons.blowups, neurons.blowups)
    assert np.abs(ref_springs).max() > 0.01  # the schedule pushed the skin
