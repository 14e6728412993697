"""The leapfrog stepper of the linear mechanics (large meshes): against solve_ivp on the same
equations at 16x16, second order, stable, and the compiled sensor block at 16x16."""

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from skinhil import SkinModel, SkinParams
from skinhil.model.mechanics.leapfrog import DTYPE, LeapfrogMechanics
from skinhil.model.mechanics.linear import assemble, free_block, free_dofs, sensor_matrix
from skinhil.model.neurons import NeuronPopulation, simulate_spikes
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import at_size, direction_conditions, paper_stimuli, random_schedule


def _solve_ivp_reference(model: SkinModel, force: np.ndarray, dt: float) -> np.ndarray:
    """Spring forces (N) at each step start of ``M q'' + C q' + K q = f``, assembled sparse,
    integrated by solve_ivp (DOP853, tight) step by step with ``force`` (n, n_masses, 3) N
    held over each step."""
    p = model.params
    k_glob, c_glob = assemble(model.mesh, p.stiffness_n_per_m, p.damping_n_s_per_m,
                              p.tension_n)
    k = free_block(k_glob, model.mesh) / p.mass_kg
    c = free_block(c_glob, model.mesh) / p.mass_kg
    dofs = free_dofs(model.mesh)
    sense = sensor_matrix(model.mesh, p.stiffness_n_per_m)
    n = dofs.size
    x = np.zeros(2 * n)
    rows = []
    for f in force:
        rows.append(sense @ x[:n])
        acc = f.ravel()[dofs] / p.mass_kg

        def rhs(_t: float, y: np.ndarray, acc: np.ndarray = acc) -> np.ndarray:
            return np.concatenate([y[n:], acc - k @ y[:n] - c @ y[n:]])

        x = solve_ivp(rhs, (0.0, dt), x, method="DOP853", rtol=1e-10, atol=1e-16).y[:, -1]
    return np.array(rows)


def test_leapfrog_16x16_matches_solve_ivp() -> None:
    model = SkinModel(SkinParams(size=(16, 16), readout="axial"))  # the reference reads Cy q
    assert model.linear_regime == "leapfrog" and model.n_springs == 3538
    stim = at_size(paper_stimuli()[0], (16, 16))
    dt, n = 1e-4, 150
    force = stim.force_at(np.arange(n) * dt)
    ours = model.stepper(dt).advance(force)
    ref = _solve_ivp_reference(model, force, dt)
    err = np.abs(ours - ref).max() / np.abs(ref).max()
    print(f"16x16 leapfrog vs solve_ivp: max error {err:.2e} of the peak force")
    assert err < 5e-3, err  # second order at ω·dt ≈ 0.2 (module docstring of the stepper)
    assert np.abs(ref).max() > 0.05  # the press moves the skin (N)


def _error_vs_exact(dt: float, tension_n: float) -> float:
    """Largest leapfrog error against the exact ZOH of the same 8x8 mesh, of the peak force."""
    stim = at_size(paper_stimuli()[3], (8, 8))
    exact, leap = (SkinModel(SkinParams(size=(8, 8), tension_n=tension_n, linear_stepper=how,
                                        mechanics="linear"))
                   .simulate(stim, 0.05, dt) for how in ("exact", "leapfrog"))
    return float(np.abs(exact - leap).max() / np.abs(exact).max())


def test_only_free_masses_are_stepped_and_fixed_springs_read_zero() -> None:
    model = SkinModel(SkinParams(size=(12, 9)))
    mech = LeapfrogMechanics(model.mesh, 1e-4, 50.0, 0.05, 0.0, 1e-4)
    bands = mech.operands.moving
    assert len(bands) == 2  # layers 1 and 2, from the first free mass to the last
    stepped = np.concatenate([np.arange(s0, s0 + n) for s0, n in bands])
    moves = stepped[mech.operands.inv_m[stepped] > 0]  # a fixed mass's 1/m is 0
    assert np.array_equal(moves, mech.slots[model.mesh.free])  # each free mass, in its slot
    push = np.zeros((200, model.n_masses, 3))
    push[:, model.mesh.free, 2] = -0.01
    out = mech.advance(push)
    between_fixed = model.mesh.fixed[model.mesh.springs].all(axis=1)
    assert np.all(out[:, between_fixed] == 0.0) and np.abs(out[:, ~between_fixed]).max() > 0
    assert np.all(mech.displacement_m()[model.mesh.fixed] == 0.0)
    unused = np.setdiff1d(np.arange(mech.state.shape[2]), mech.slots)
    assert unused.size and np.all(mech.state[:, :, unused] == 0.0)  # padding never moves


def test_leapfrog_is_second_order() -> None:
    coarse, fine = _error_vs_exact(1e-4, 0.0), _error_vs_exact(5e-5, 0.0)
    assert coarse < 5e-3
    assert 3.0 < coarse / fine < 5.0, (coarse, fine)


def test_leapfrog_substeps_keep_tension_accurate() -> None:
    # a 0.5 N tension makes the fastest mode 3.7x faster: substeps keep ω·h <= 0.25
    assert _error_vs_exact(1e-4, 0.5) < 5e-3


@pytest.mark.parametrize("damping, tension, dt", [(0.05, 0.0, 1e-4), (0.2, 0.0, 1e-4),
                                                  (0.05, 1.0, 3e-4), (0.0, 0.0, 1e-3)])
def test_leapfrog_substeps_keep_it_stable(damping: float, tension: float, dt: float) -> None:
    # spectral radius of the step map with zero input (state q, v, w of the free masses): a
    # property of the scheme, so in double precision (single precision's rounding is 6e-8)
    model = SkinModel(SkinParams(damping_n_s_per_m=damping, tension_n=tension))
    mech = LeapfrogMechanics(model.mesh, 1e-4, 50.0, damping, tension, dt, dtype=np.float64)
    free = model.mesh.free
    n = 3 * free.size
    step = np.zeros((3 * n, 3 * n))
    zero = np.zeros((1, model.n_masses, 3))
    for col in range(3 * n):
        mech.reset()
        mech.state[col // n, col % 3, mech.slots[free[(col % n) // 3]]] = 1.0
        mech.advance(zero)
        step[:, col] = np.concatenate([mech.of_masses(k)[free].ravel() for k in range(3)])
    assert np.abs(np.linalg.eigvals(step)).max() <= 1.0 + 1e-9


def test_sensor_block_16x16_equals_stepper_then_neurons() -> None:
    model = SkinModel(SkinParams(size=(16, 16)))
    schedule = random_schedule([at_size(s, (16, 16)) for s in direction_conditions()], 3,
                               seed=2, lead_s=0.0)
    sensor = SkinSensor(model, 1e-4, snr_db=20.0, seed=5)
    springs, spikes = sensor.advance_schedule(schedule, 3000)
    stepper = model.stepper(1e-4)
    ref = stepper.advance(schedule.force_at(np.arange(3000) * 1e-4, (16, 16)))
    pop = NeuronPopulation(model.n_springs, snr_db=20.0, seed=5)
    np.testing.assert_allclose(springs, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    assert np.array_equal(spikes, pop.step_block(ref, 1e-4))
    assert spikes.sum() > 0


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="one core")
def test_two_threads_give_the_same_spikes() -> None:
    # 3,538 channels: four noise blocks shared by two threads, the same draws per channel
    model = SkinModel(SkinParams(size=(16, 16)))
    schedule = random_schedule([at_size(s, (16, 16)) for s in direction_conditions()], 2,
                               seed=1, lead_s=0.0)
    one = SkinSensor(model, 1e-4, snr_db=10.0, seed=3)
    two = SkinSensor(model, 1e-4, snr_db=10.0, seed=3, threads=2)
    assert (one.threads, two.threads) == (1, 2)
    for _ in range(3):
        f1, s1 = one.advance_schedule(schedule, 700)
        f2, s2 = two.advance_schedule(schedule, 700)
        np.testing.assert_allclose(f1, f2, rtol=0, atol=1e-15)
        assert np.array_equal(s1, s2) and s1.any()


def test_single_precision_gives_the_spikes_of_double_precision() -> None:
    # the leapfrog's numerical contract (module docstring, "Precision"): in single precision
    # the spring forces lie within 1e-6 of the peak of the double-precision reference (the
    # scheme's own error is 1e-3), and the spikes are the reference's, spike for spike:
    # noise-free on the paper's five stimuli and the nine direction conditions, and at 10 dB
    # with the same noise streams under a random schedule
    model = SkinModel(SkinParams.at_amplitude("paper", size=(16, 16)))  # large deformations
    p = model.params
    assert DTYPE == np.float32 and model.stepper(1e-4).dtype == np.float32

    def reference() -> LeapfrogMechanics:
        return LeapfrogMechanics(model.mesh, p.mass_kg, p.stiffness_n_per_m,
                                 p.damping_n_s_per_m, p.tension_n, 1e-4, dtype=np.float64)

    spikes = 0
    for stim in paper_stimuli() + direction_conditions():
        force = at_size(stim, (16, 16)).force_at(np.arange(3000) * 1e-4)
        single, double = model.stepper(1e-4).advance(force), reference().advance(force)
        assert single.dtype == np.float32 and double.dtype == np.float64
        assert np.abs(single - double).max() <= 1e-6 * np.abs(double).max()
        want = simulate_spikes(double, 1e-4)
        assert np.array_equal(simulate_spikes(single, 1e-4), want), stim.name
        spikes += int(want.sum())
    assert spikes > 1000  # 1,787 spikes compared
    schedule = random_schedule([at_size(s, (16, 16)) for s in direction_conditions()], 4,
                               seed=3, lead_s=0.0)
    force = schedule.force_at(np.arange(8000) * 1e-4, (16, 16))
    noisy = [NeuronPopulation(model.n_springs, snr_db=10.0, seed=9).step_block(
        mech.advance(force), 1e-4) for mech in (model.stepper(1e-4), reference())]
    assert np.array_equal(noisy[0], noisy[1]) and noisy[0].sum() > 1000
