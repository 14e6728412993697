"""The geometric mechanics' strip kernel against its former per-spring formulation
(tests/geometric_reference.py): the same spring forces and positions to rounding, on every
readout, with and without a baseline tension, on square and oblong skins, through a large
deformation and the release after it."""

import numpy as np
import pytest
from geometric_reference import ReferenceGeometric

from skinhil import SkinModel, SkinParams
from skinhil.model.mechanics.geometric import GeometricMechanics
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import Schedule, ScheduledStimulus, at_size, paper_stimuli

TOLERANCE = 1e-11
"""Largest difference allowed, as a fraction of the peak spring force: double precision
rounds at 1.1e-16 of a value, and the two formulations differ only in the order of their
operations (measured: at most 1.4e-14 of the peak, at 10x10 over 3,000 steps)."""


@pytest.mark.parametrize(("size", "tension", "readout"), [
    ((6, 6), 0.0, "length"), ((6, 6), 0.3, "axial"), ((4, 7), 0.1, "length"),
    ((10, 10), 0.0, "length")])
def test_the_strip_kernel_is_the_per_spring_formulation_to_rounding(
        size: tuple[int, int], tension: float, readout: str) -> None:
    model = SkinModel(SkinParams.at_amplitude(  # the paper regime: large deformations
        "paper", mechanics="geometric", size=size, tension_n=tension, readout=readout))
    g = model.stepper(1e-4 if tension == 0 else 2e-5)
    assert isinstance(g, GeometricMechanics)
    ref = ReferenceGeometric(g)
    stim = at_size(paper_stimuli()[2], size)  # the oblique press: a large deformation
    forces = stim.force_at(np.arange(2400) * g.dt_s)  # pressed, then released at 0.12 s
    ours, theirs = g.advance(forces), ref.advance(forces)
    peak = np.abs(theirs).max()
    assert peak > 0.01  # N: a real deformation
    assert np.abs(ours - theirs).max() <= TOLERANCE * peak
    assert np.abs(g.p - ref.p).max() <= TOLERANCE * model.params.spacing_m
    assert np.abs(g.v - ref.v).max() <= TOLERANCE * np.abs(ref.v).max() + 1e-300
    # the preload is the same net force at rest on the free masses (to rounding of k·L0;
    # on the fixed ones it acts on nothing), and rest stays exactly at rest: it is the strip
    # pass's own at zero displacement
    scale = model.params.stiffness_n_per_m * model.params.spacing_m + tension
    free = ~model.fixed
    np.testing.assert_allclose(g.preload[free], ref.preload[free], rtol=0,
                               atol=TOLERANCE * scale)
    g.reset()
    assert not g.advance(np.zeros((50, model.n_masses, 3))).any()
    assert not g.state.any()


def test_the_fused_sensor_step_is_the_stepper_and_the_neurons() -> None:
    # one compiled call per block under a schedule: the springs of the stepper's advance on
    # the schedule's forces, and the spikes of the neurons stepped on them
    model = SkinModel(SkinParams(mechanics="geometric"))
    schedule = Schedule((ScheduledStimulus(0.002, paper_stimuli()[0], 1),))
    fused = SkinSensor(model, 1e-4, snr_db=10.0, seed=4)
    stepper = model.stepper(1e-4)
    neurons = SkinSensor(model, 1e-4, snr_db=10.0, seed=4).neurons
    spiked = 0
    for block in range(30):
        springs, spikes = fused.advance_schedule(schedule, 10)
        t = (block * 10 + np.arange(10)) * 1e-4
        want = stepper.advance(schedule.force_at(t, model.size))
        np.testing.assert_allclose(springs, want, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(spikes, neurons.step_block(springs, 1e-4))
        spiked += int(spikes.sum())
    assert spiked > 0
