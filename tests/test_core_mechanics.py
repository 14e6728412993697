"""Both mechanics against scipy's solve_ivp, force balance, linearity, energy, damping."""

import math
from dataclasses import replace

import numpy as np
import pytest
from geometric_reference import ReferenceGeometric
from scipy.integrate import solve_ivp

from skinhil import SkinModel, SkinParams, Stimulus, paper_stimuli
from skinhil.model.mechanics.geometric import GeometricMechanics


def _zoh_reference(rhs, x0: np.ndarray, stim: Stimulus, dt: float, n: int,
                   out_fn) -> np.ndarray:
    """solve_ivp (DOP853, tight) step by step with the input held over each step."""
    x = x0.copy()
    rows = []
    for k in range(n):
        rows.append(out_fn(x))
        f = stim.force_at(np.array([k * dt]))[0]
        sol = solve_ivp(lambda t, y, f=f: rhs(y, f), (0.0, dt), x, method="DOP853",
                        rtol=1e-12, atol=1e-18)
        x = sol.y[:, -1]
    return np.array(rows)


def test_linear_matches_solve_ivp_on_paper_stimulus_1() -> None:
    model = SkinModel(SkinParams(mechanics="linear", readout="axial"))  # the reference: Cy q
    stim = paper_stimuli()[0]
    dt, n = 1e-3, 40
    ours = model.simulate(stim, n * dt, dt)
    lin = model.stepper(dt)
    a, b = lin.a, lin.b  # type: ignore[attr-defined]

    def rhs(y: np.ndarray, f: np.ndarray) -> np.ndarray:
        return a @ y + b @ f.ravel()[lin.dofs]  # type: ignore[attr-defined]

    ref = _zoh_reference(rhs, np.zeros(a.shape[0]), stim, dt, n,
                         lambda x: lin.cy @ x[: lin.dofs.size])  # type: ignore[attr-defined]
    err = np.abs(ours - ref).max() / np.abs(ref).max()
    assert err < 1e-6


def _geometric_reference(stim: Stimulus, dt: float, t_end: float) -> np.ndarray:
    g = SkinModel(SkinParams(mechanics="geometric")).stepper(dt)
    assert isinstance(g, GeometricMechanics)
    free = g.free
    ref = ReferenceGeometric(g)

    def rhs(y: np.ndarray, f: np.ndarray) -> np.ndarray:
        p = g.rest_positions.copy()
        v = np.zeros_like(p)
        p[free] = y[: 3 * free.size].reshape(-1, 3)
        v[free] = y[3 * free.size:].reshape(-1, 3)
        acc = (ref.forces(p, v) - ref.preload + f)[free] * g.inv_m
        return np.concatenate([v[free].ravel(), acc.ravel()])

    def out(y: np.ndarray) -> np.ndarray:
        p = g.rest_positions.copy()
        p[free] = y[: 3 * free.size].reshape(-1, 3)
        d = p[g.springs[:, 1]] - p[g.springs[:, 0]]
        return g.k * (np.linalg.norm(d, axis=1) - g.rest_lengths)

    y0 = np.concatenate([g.rest_positions[free].ravel(), np.zeros(3 * free.size)])
    return _zoh_reference(rhs, y0, stim, dt, int(round(t_end / dt)) + 1, out)[-1]


def test_geometric_converges_at_fourth_order() -> None:
    stim = paper_stimuli()[2]  # input 3, the oblique press: a large deformation
    t_end = 4e-3
    errors = []
    for dt in (1e-4, 5e-5):
        model = SkinModel(SkinParams(mechanics="geometric"))
        n = int(round(t_end / dt)) + 1
        ours = model.simulate(stim, n * dt, dt)[-1]
        errors.append(np.abs(ours - _geometric_reference(stim, dt, t_end)).max())
    order = math.log2(errors[0] / errors[1])
    assert 3.5 < order < 4.6, (errors, order)


def _constant(force: tuple[float, float, float], mass: int = 15) -> Stimulus:
    return Stimulus("const", {mass: force}, indentation_s=10.0, decay_tau_s=math.inf)


@pytest.mark.parametrize("mechanics", ["linear", "geometric"])
def test_force_balance_at_steady_state(mechanics: str) -> None:
    # the linear dynamics' forces act along the rest directions: its axial readout balances
    readout = "axial" if mechanics == "linear" else "length"
    # the paper regime (large deformations, K 50 N/m), damping raised to 0.2 N·s/m
    model = SkinModel(replace(SkinParams.at_amplitude("paper", mechanics=mechanics,
                                                      readout=readout), damping_n_s_per_m=0.2))
    stepper = model.stepper(4e-5)  # heavy damping needs a small RK4 step
    f_ext = np.zeros((7500, 77, 3))
    f_ext[:, 14] = (0.1, 0.05, -0.2)
    forces = stepper.advance(f_ext)[-1]
    if mechanics == "linear":
        pos = model.positions
    else:
        assert isinstance(stepper, GeometricMechanics)
        pos = stepper.p
    d = pos[model.springs[:, 1]] - pos[model.springs[:, 0]]
    e = d / np.linalg.norm(d, axis=1)[:, None]
    net = f_ext[-1].copy()
    np.add.at(net, model.springs[:, 0], forces[:, None] * e)
    np.add.at(net, model.springs[:, 1], -forces[:, None] * e)
    free = ~model.fixed
    assert np.abs(net[free]).max() < 1e-6 * 0.2


def test_linear_in_the_force() -> None:
    # the length change is not linear in q
    model = SkinModel(SkinParams(mechanics="linear", readout="axial"))
    base = model.simulate(Stimulus("s", {15: (0.1, 0.2, -0.3)}), 0.05)
    double = model.simulate(Stimulus("s", {15: (0.2, 0.4, -0.6)}), 0.05)
    np.testing.assert_allclose(double, 2 * base, rtol=1e-12, atol=1e-15)


def test_geometric_agrees_with_linear_for_small_forces() -> None:
    lin = SkinModel(SkinParams(mechanics="linear"))
    geo = SkinModel(SkinParams(mechanics="geometric"))
    rel = []
    for scale in (1e-2, 1e-3, 1e-4):
        stim = Stimulus("s", {15: (0.3 * scale, 0.2 * scale, -0.5 * scale)})
        a = lin.simulate(stim, 0.03)
        b = geo.simulate(stim, 0.03)
        rel.append(np.abs(a - b).max() / np.abs(a).max())
    assert rel[0] > rel[1] > rel[2]
    assert rel[2] < 1e-3
    assert rel[1] / rel[2] > 5  # shrinks in proportion to the force


def test_energy_conserved_without_damping() -> None:
    dt = 1e-4
    params = SkinParams(damping_n_s_per_m=0.0, mechanics="linear")
    kick = np.zeros((50, 77, 3))
    kick[:, 14] = (0.2, 0.1, -0.3)
    rest = np.zeros((2000, 77, 3))
    # linear: exact ZOH conserves ½vᵀMv + ½qᵀKq exactly
    lin = SkinModel(params).stepper(dt)
    lin.advance(kick)
    n = lin.dofs.size  # type: ignore[attr-defined]
    k_mat = -lin.a[n:, :n] * params.mass_kg  # type: ignore[attr-defined]

    def energy(x: np.ndarray) -> float:
        q, v = x[:n], x[n:]
        return float(0.5 * params.mass_kg * v @ v + 0.5 * q @ k_mat @ q)

    e0 = energy(lin.state())  # type: ignore[attr-defined]
    lin.advance(rest)
    assert abs(energy(lin.state()) - e0) / e0 < 1e-9  # type: ignore[attr-defined]
    # geometric: RK4's energy error shrinks ~ dt^4
    drifts = []
    for step in (1e-4, 5e-5):
        geo = SkinModel(SkinParams(damping_n_s_per_m=0.0, mechanics="geometric")).stepper(step)
        assert isinstance(geo, GeometricMechanics)
        geo.advance(np.zeros((int(5e-3 / step), 77, 3)) + kick[0])
        g0 = geo.energy_j()
        geo.advance(np.zeros((int(0.05 / step), 77, 3)))
        drifts.append(abs(geo.energy_j() - g0) / g0)
    assert drifts[1] < 1e-3, drifts
    assert drifts[0] / drifts[1] > 8, drifts  # ≈ 16 for a 4th-order method


@pytest.mark.parametrize("mechanics", ["linear", "geometric"])
def test_forces_decay_after_indentation(mechanics: str) -> None:
    model = SkinModel(SkinParams(mechanics=mechanics))  # type: ignore[arg-type]
    f = model.simulate(paper_stimuli()[1], 0.4)
    during = np.abs(f[:2500]).max()
    after = np.abs(f[-500:]).max()
    assert during > 0.01 and after < 1e-3 * during
