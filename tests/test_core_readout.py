"""What each spring reports, in every kernel: the length change (default) or the axial
projection, against a numpy reference on the stepper's own displacements."""

import numpy as np
import pytest

from skinhil import SkinModel, SkinParams, Stimulus
from skinhil.model.mechanics.geometric import GeometricMechanics
from skinhil.model.mechanics.leapfrog import LeapfrogMechanics
from skinhil.model.mechanics.linear import LinearMechanics
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import at_size, direction_conditions, paper_stimuli

STEPS = 120


def _reference(model: SkinModel, q: np.ndarray, readout: str) -> np.ndarray:
    """Spring forces (N) from displacements q (n_masses, 3) m, straight from the definition:
    k(|L0 e + d| − L0) or k eᵀd, d = q_j − q_i."""
    i, j = model.springs[:, 0], model.springs[:, 1]
    rest_vec = model.positions[j] - model.positions[i]
    l0 = np.linalg.norm(rest_vec, axis=1)
    d = q[j] - q[i]
    k = model.params.stiffness_n_per_m
    if readout == "axial":
        return k * np.einsum("sa,sa->s", rest_vec / l0[:, None], d)
    return k * (np.linalg.norm(rest_vec + d, axis=1) - l0)


CASES = [  # (params, kernel) : every stepper the model builds
    (dict(mechanics="linear"), LinearMechanics),  # modal (no tension)
    (dict(mechanics="linear", tension_n=0.05), LinearMechanics),  # full state space
    (dict(mechanics="linear", size=(12, 12)), LeapfrogMechanics),
    (dict(mechanics="linear", tension_n=0.5, linear_stepper="leapfrog"),
     LeapfrogMechanics),  # substeps
    (dict(mechanics="geometric"), GeometricMechanics),
]


@pytest.mark.parametrize("readout", ["length", "axial"])
@pytest.mark.parametrize(("extra", "kind"), CASES)
def test_every_kernel_reports_the_readout_of_its_displacements(extra: dict, kind: type,
                                                               readout: str) -> None:
    model = SkinModel(SkinParams(readout=readout, **extra))  # type: ignore[arg-type]
    stepper = model.stepper(1e-4)
    assert isinstance(stepper, kind)
    if kind is LinearMechanics:
        assert stepper.modal == ("tension_n" not in extra)
    stim = at_size(direction_conditions()[2], model.size)  # 0.5 N along x on M15
    force = stim.force_at(np.arange(STEPS) * 1e-4)
    ours, ref = [], []
    for row in force:  # row k of advance is the readout at the start of step k
        ref.append(_reference(model, stepper.displacement_m(), readout))
        ours.append(stepper.advance(row[None])[0])
    ours_a, ref_a = np.array(ours), np.array(ref)
    err = np.abs(ours_a - ref_a).max() / np.abs(ref_a).max()
    # double precision to 1e-12 of the peak; the leapfrog's single precision (rounding 6e-8)
    # to 1e-6
    assert err <= (1e-6 if ours_a.dtype == np.float32 else 1e-12), err
    assert np.abs(ref_a).max() > 0.01  # a real deformation (N)


def test_the_readouts_differ_at_the_papers_forces() -> None:
    """At 0.5 N the linear mesh moves by a large fraction of its spring lengths: the two
    readouts disagree there (which is why the choice matters)."""
    stim = direction_conditions()[2]
    length, axial = (SkinModel(SkinParams.at_amplitude("paper", mechanics="linear",
                                                       readout=r)).simulate(stim, 0.05)
                     for r in ("length", "axial"))
    assert np.abs(length - axial).max() > 0.2 * np.abs(axial).max()
    # the default skin (the small amplitude: 1/100 of the displacement) keeps them within
    # a few percent: its strain stays inside the bound
    length, axial = (SkinModel(SkinParams(mechanics="linear", readout=r)).simulate(stim, 0.05)
                     for r in ("length", "axial"))
    assert np.abs(length - axial).max() < 0.05 * np.abs(axial).max()


def test_readouts_agree_for_small_displacements() -> None:
    stim = paper_stimuli()[2]
    tiny = Stimulus("tiny", {m: tuple(1e-5 * np.asarray(f)) for m, f in stim.forces.items()})
    length, axial = (SkinModel(SkinParams(readout=r)).simulate(tiny, 0.03)  # type: ignore[arg-type]
                     for r in ("length", "axial"))
    assert np.abs(length - axial).max() < 1e-4 * np.abs(axial).max()


@pytest.mark.parametrize("extra", [dict(mechanics="linear"), dict(size=(12, 12))])
def test_fused_board_kernels_equal_stepper_then_neurons(extra: dict) -> None:
    """The board's compiled blocks (modal and leapfrog) report the default readout: the same
    spring forces and spikes as the stepper followed by the neurons."""
    model = SkinModel(SkinParams(**extra))  # type: ignore[arg-type]
    assert model.params.readout == "length"
    stim = at_size(direction_conditions()[4], model.size)
    force = stim.force_at(np.arange(400) * 1e-4)
    fused = SkinSensor(model, snr_db=10.0, seed=3)
    assert fused.fused
    springs_f, spikes_f = fused.advance(force)
    plain = SkinSensor(model, snr_db=10.0, seed=3)
    springs_p = plain.stepper.advance(force)
    spikes_p = plain.neurons.step_block(springs_p, plain.dt_s)
    assert np.array_equal(springs_f, springs_p) and np.array_equal(spikes_f, spikes_p)
    assert spikes_f.any()
