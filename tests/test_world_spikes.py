"""Spikes follow the world: a sliding sphere's place in the spiking channels' centroid, a
vibration's phase in the spike times (docs/contact.md states the figures)."""

from __future__ import annotations

import numpy as np

from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.world import Contact, Indenter, Scene, TouchSensor, Trajectory, truth_records

DT = 1e-4
BIN_S = 0.02


def play(contact: Contact, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, SkinModel]:
    """Truth per step and the bool spikes of a noise-free skin of ``size`` under
    ``contact``."""
    model = SkinModel(SkinParams(size=size))
    touch = TouchSensor(SkinSensor(model, DT, state_forces=True), Scene((contact,)))
    touch.start(0.0)
    n = int(round(contact.end_s / DT))
    _, spikes, raw = touch.advance_schedule(Schedule(()), n)
    return truth_records(raw, np.arange(n) * 100), spikes, model


def test_the_spiking_centroid_follows_a_sliding_sphere() -> None:
    path = Trajectory.slide((-5e-3, 0.0), (5e-3, 0.0), 20e-3, 0.3, load=True)  # 0.3 N
    truth, spikes, model = play(Contact(Indenter("sphere", radius_m=3e-3), path), (16, 16))
    middle = 0.5 * (model.positions[model.springs[:, 0]] + model.positions[model.springs[:, 1]])
    step, channel = np.nonzero(spikes)
    t = step * DT
    centroid, place = [], []
    for end in np.arange(0.07 + BIN_S, 0.07 + 0.5 + 1e-9, BIN_S):  # the slide, in 20 ms bins
        inside = (t >= end - BIN_S) & (t < end)
        if inside.sum() >= 3:
            centroid.append(middle[channel[inside], 0].mean())
            place.append(np.interp(end - BIN_S / 2, truth["t_us"] * 1e-6,
                                   truth["indenter_x_mm"]))
    assert len(centroid) >= 20
    r = np.corrcoef(centroid, place)[0, 1]
    assert r >= 0.8  # measured 0.995 (324 spikes, 20 bins)


def test_spikes_lock_to_the_phase_of_a_100_hz_vibration() -> None:
    press = Trajectory.press(0.0, 0.0, 20e-6, ramp_s=0.02, hold_s=0.5)  # ~0.5 N
    shaken = press.with_vibration(8e-6, 100.0)
    _, spikes, _ = play(Contact(Indenter("flat", radius_m=1.5e-3), shaken), (6, 6))
    t = np.nonzero(spikes)[0] * DT
    t = t[(t > 0.1) & (t < 0.52)]  # the hold, after the ramp
    strength = abs(np.exp(2j * np.pi * 100.0 * t).mean())
    assert len(t) >= 50
    assert strength >= 0.45  # measured 0.806 over 70 spikes (Rayleigh p ~ 1e-20)
