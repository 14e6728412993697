"""The contact model against analytic cases (docs/contact.md): a flat indenter's static force
balance, the onset of sliding at mu_s·N, stick-slip of a sliding sphere and none without
friction, energy that only decays after release, and the stimuli's spikes unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import diags
from scipy.sparse.linalg import spsolve

from skinhil.errors import ConfigError
from skinhil.model.mechanics.linear import assemble, free_block, free_dofs
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule, ScheduledStimulus, builtin_catalog
from skinhil.world import (
    Contact,
    ContactParams,
    Indenter,
    Scene,
    TouchSensor,
    Trajectory,
    truth_records,
)

DT = 1e-4
LEAPFROG = SkinParams(mechanics="linear", linear_stepper="leapfrog")
"""The linear mechanics stepped by the leapfrog (its static solution is a linear solve)."""
PAD = Indenter("flat", radius_m=1.2e-3)
"""A flat pad that covers five masses when centred on one (M15's neighbours are 1 mm away,
the diagonal ones 1.41 mm)."""
AT = (-0.5e-3, 0.5e-3)
"""M15, an interior mass of the 6x6 skin (x, y m)."""


def play(contact: Contact, seconds: float, params: SkinParams = LEAPFROG,
         schedule: Schedule | None = None) -> tuple[np.ndarray, np.ndarray, TouchSensor]:
    """Truth records every step, spikes, and the touch sensor after ``seconds``."""
    sensor = SkinSensor(SkinModel(params), DT, state_forces=True)
    touch = TouchSensor(sensor, Scene((contact,)))
    touch.start(0.0)
    n = int(round(seconds / DT))
    _, spikes, raw = touch.advance_schedule(schedule or Schedule(()), n)
    return truth_records(raw, np.arange(n) * 100), spikes, touch


def test_flat_indenter_held_at_depth_reaches_the_static_balance() -> None:
    depth = 0.2e-3
    contact = Contact(PAD, Trajectory.press(*AT, depth, ramp_s=0.02, hold_s=0.5),
                      mu_static=0.0, mu_kinetic=0.0)
    rec, _, touch = play(contact, 0.3)
    model = touch.sensor.model
    # the static solution: (K + k_n·P) q = −k_n·depth·P·1 on the free dofs, P the z dofs
    # of the touching masses (frictionless: no tangential springs)
    p = model.params
    k_glob, _ = assemble(model.mesh, p.stiffness_n_per_m, p.damping_n_s_per_m, 0.0)
    kff = free_block(k_glob, model.mesh)
    dofs = free_dofs(model.mesh)
    top = model.positions[:, 2] == 0
    near = np.hypot(model.positions[:, 0] - AT[0], model.positions[:, 1] - AT[1]) < 1.2e-3
    touching = np.flatnonzero(top & near & ~model.fixed)
    assert len(touching) == 5
    pz = np.isin(dofs, 3 * touching + 2).astype(float)
    kn = touch.params.normal_stiffness_n_per_m
    assert kn == ContactParams().normal_stiffness_n_per_m  # the default skin's contact
    q = spsolve((kff + diags(kn * pz)).tocsc(), -kn * depth * pz)
    normal = float(np.sum(kn * (q[pz > 0] + depth)))
    assert rec["nodes"][-1] == 5
    assert rec["normal_n"][-1] == pytest.approx(normal, rel=1e-5)  # measured 4e-8
    moved = touch.sensor.stepper.displacement_m().ravel()[dofs]
    assert np.abs(moved - q).max() < 1e-5 * np.abs(q).max()  # measured 1.4e-7
    # each touching mass: its penetration's force balances the skin's pull on it
    assert np.abs(moved[pz > 0] + depth).min() > 0  # every one still pressed


def test_a_pad_sticks_below_mu_n_and_slides_above() -> None:
    mu, load = 0.5, 0.1
    keys = np.array([(0, 0, 0, load), (0.05, 0, 0, load), (2.05, 1.5 * mu * load, 0, load)])
    ramp = Trajectory(keys, normal="force", tangential="force", origin_m=AT)
    rec, _, _ = play(Contact(PAD, ramp, mu_static=mu, mu_kinetic=mu), 2.0)
    capacity = mu * rec["normal_n"]
    ratio = rec["tangential_x_n"] / np.where(capacity > 0, capacity, np.inf)
    gross = np.flatnonzero(rec["slip"] == 3)[0]
    assert 0.98 <= ratio[gross] <= 1.02  # gross slip starts at mu_s·N
    before = rec[:gross][(rec["t_us"][:gross] > 60_000) & (ratio[:gross] < 0.8)]
    assert len(before) > 5000 and np.all(before["slip"] == 1)  # all stick
    assert np.any(rec["slip"][:gross] == 2)  # partial slip (at the edge) before gross
    held = []
    for share in (0.95, 1.05):  # a constant tangential load below and above mu_s·N
        keys = np.array([(0, 0, 0, load), (0.05, 0, 0, load), (0.15, share * mu * load, 0,
                                                                  load), (0.4, share * mu * load,
                                                                          0, load)])
        rec, _, _ = play(Contact(PAD, Trajectory(keys, normal="force", tangential="force",
                                                 origin_m=AT), mu_static=mu, mu_kinetic=mu),
                         0.4)
        late = rec[rec["t_us"] > 300_000]
        speed = np.ptp(late["indenter_x_mm"]) / 0.1  # mm/s over the last 0.1 s
        held.append((speed, late["slip"][-1]))
    assert held[0][0] < 0.002 and held[0][1] in (1, 2)  # sticks: the pad stands still
    # slides on at b_t·(load − mu·N) = 0.02 m/(N·s) x 2.5 mN = 0.05 mm/s
    assert held[1][0] > 0.025 and held[1][1] == 3


def test_a_sliding_sphere_sticks_and_slips_and_not_without_friction() -> None:
    path = Trajectory.slide((-1.5e-3, 0.0), (1.5e-3, 0.0), 5e-3, 0.3e-3)
    sphere = Indenter("sphere", radius_m=3e-3)
    out = {}
    for mu in ((1.0, 0.3), (0.0, 0.0)):
        rec, _, _ = play(Contact(sphere, path, mu_static=mu[0], mu_kinetic=mu[1]), 0.6)
        sliding = rec[(rec["t_us"] >= 70_000) & (rec["t_us"] < 600_000)]
        ft = sliding["tangential_x_n"]
        drops = np.sum(ft[:-20] - ft[20:] > 0.05 * 0.3 * sliding["normal_n"][:-20])  # in 2 ms
        out[mu[0]] = (ft, sliding["slip"], drops)
    ft, slip, drops = out[1.0]
    assert set(np.unique(slip)) >= {2, 3}  # stuck masses then all slipping, in turns
    assert np.sum(np.diff(slip) != 0) >= 4 and drops > 0  # the force falls as masses let go
    ft, slip, drops = out[0.0]
    assert np.all(ft == 0) and np.all(slip == 3) and drops == 0


def test_after_release_the_skin_energy_only_decays() -> None:
    geometric = SkinParams(mechanics="geometric")
    sensor = SkinSensor(SkinModel(geometric), DT, state_forces=True)
    press = Trajectory.slide((-1e-3, 0.0), (1e-3, 0.0), 20e-3, 0.4e-3, ramp_s=0.005,
                             dwell_s=0.01)
    touch = TouchSensor(sensor, Scene((Contact(Indenter("sphere", radius_m=2e-3), press),)))
    touch.start(0.0)
    stepper = sensor.stepper
    energy = []
    for _ in range(int(round((press.duration_s + 0.05) / DT))):
        _, _, raw = touch.advance_schedule(Schedule(()), 1)
        energy.append((raw[0, 0, 9], stepper.energy_j()))  # touching masses, energy
    e = np.array(energy)
    free = np.flatnonzero(e[:, 0] == 0)
    after = e[free[free > np.argmax(e[:, 1])][0]:, 1]  # from the release on
    assert e[:, 1].max() > 1e-7
    assert np.all(np.diff(after) <= 1e-15)


def test_the_stimuli_spikes_are_the_same_with_an_idle_world() -> None:
    stim = builtin_catalog()["A"]
    schedule = Schedule((ScheduledStimulus(0.0, stim[1], stim[0]),))
    contact = Contact(PAD, Trajectory.press(*AT, 0.2e-3))
    for params in (LEAPFROG, SkinParams(mechanics="geometric")):
        plain = SkinSensor(SkinModel(params), DT, snr_db=10.0, seed=3)
        ref = [plain.advance_schedule(schedule, 1000) for _ in range(2)]
        touching = SkinSensor(SkinModel(params), DT, snr_db=10.0, seed=3, state_forces=True)
        touch = TouchSensor(touching, Scene((contact,)))  # never started: nothing touches
        got = [touch.advance_schedule(schedule, 1000) for _ in range(2)]
        for (f0, s0), (f1, s1, _) in zip(ref, got, strict=True):
            assert np.array_equal(f0, f1) and np.array_equal(s0, s1)


def test_the_exact_linear_stepper_refuses_contact_and_auto_picks_the_leapfrog() -> None:
    exact = SkinModel(SkinParams(mechanics="linear", linear_stepper="exact"))
    with pytest.raises(ConfigError, match="cannot carry a contact"):
        SkinSensor(exact, DT, state_forces=True)
    auto = SkinSensor(SkinModel(SkinParams(mechanics="linear")), DT, state_forces=True)
    assert type(auto.stepper).__name__ == "LeapfrogMechanics"


def test_a_force_controlled_load_follows_its_set_point_changed_at_run_time() -> None:
    sensor = SkinSensor(SkinModel(LEAPFROG), DT, state_forces=True)
    press = Trajectory.press(*AT, 0.1, ramp_s=0.0, hold_s=1.0, load=True)  # 0.1 N
    touch = TouchSensor(sensor, Scene((Contact(PAD, press),)))
    touch.start(0.0)
    _, _, raw = touch.advance_schedule(Schedule(()), 1500)
    assert truth_records(raw[-1:], [0])["normal_n"][0] == pytest.approx(0.1, rel=1e-3)
    touch.world.set_load(0, 0.25)  # a grip set-point
    _, _, raw = touch.advance_schedule(Schedule(()), 1500)
    last = truth_records(raw[-1:], [0])[0]
    assert last["normal_n"] == pytest.approx(0.25, rel=1e-3) and last["load_n"] == 0.25
    with pytest.raises(ConfigError, match="no load to set"):
        TouchSensor(SkinSensor(SkinModel(LEAPFROG), DT, state_forces=True),
                    Scene((Contact(PAD, Trajectory.press(*AT, 1e-4)),))).world.set_load(0, 1.0)
