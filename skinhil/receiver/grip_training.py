"""Fit the reference grip controller's load readout offline, on simulated lifts (the way
:mod:`skinhil.receiver.training` fits the stimulus decoder): the same skin, noise and held
object as the board's, lifted at a few constant grips that hold it; a ridge regression of the
object's load (N, the simulation's truth) on the channels' rates
(:class:`~skinhil.receiver.grip_reflex.ChannelRates`) at every bin. The live link carries no
truth: the readout is fitted before the run, like any decoder's calibration.
"""

from __future__ import annotations

import numpy as np

from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.sensor import SkinSensor
from skinhil.model.skin import SkinModel, SkinParams
from skinhil.model.stimuli import Schedule
from skinhil.plant import GraspParams, HeldObject, lift_scene
from skinhil.receiver.grip_reflex import ChannelRates, LoadReadout, ReflexParams
from skinhil.world import TouchSensor

TRAINING_GRIPS_N = (0.8, 1.0, 1.2)
"""Constant grips of the training lifts (N): each holds the default object."""
RIDGE = 3e4
"""Ridge penalty (spikes²/s², the squared rates' scale) of the fit."""


def simulate_lifts(grip_n: float, lifts: int, snr_db: float, seed: int,
                   params: GraspParams | None = None, size: MeshSize = PAPER_SIZE,
                   dt_s: float = 1e-4, tick_s: float = 1e-3
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``lifts`` lifts at a constant grip: the events (EVENT_DTYPE, board time) and the
    held object's truth (:data:`skinhil.plant.HELD_DTYPE`, one row per tick)."""
    params = params or GraspParams()
    sensor = SkinSensor(SkinModel(SkinParams(size=size)), dt_s, snr_db, seed,
                        state_forces=True)
    touch = TouchSensor(sensor, lift_scene(params, lifts))
    steps = int(round(tick_s / dt_s))
    plant = HeldObject(params, touch.world, int(round(tick_s * 1e6)))
    plant.grip_n = grip_n
    touch.start(0.0)
    empty = Schedule(())
    events, rows = [], []
    for k in range(int(round(lifts * params.period_s / tick_s))):
        plant.before_tick()
        _, spikes, raw = touch.advance_schedule(empty, steps)
        rows.append(plant.after_tick(int(round(k * tick_s * 1e6)), k * tick_s, dt_s, raw))
        events.append(sensor.events(spikes, k * steps))
    return np.concatenate(events), np.concatenate(rows)


def fit_readout(snr_db: float, seed: int = 0, lifts: int = 2,
                reflex: ReflexParams | None = None, params: GraspParams | None = None,
                size: MeshSize = PAPER_SIZE) -> LoadReadout:
    """The load readout fitted on ``lifts`` lifts at each of :data:`TRAINING_GRIPS_N`."""
    reflex = reflex or ReflexParams()
    feats, loads = [], []
    for i, grip in enumerate(TRAINING_GRIPS_N):
        events, held = simulate_lifts(grip, lifts, snr_db, seed + i, params, size)
        rates = ChannelRates(SkinModel(SkinParams(size=size)).n_springs, reflex.bin_s,
                             reflex.tau_s)
        tick_us = int(held["t_us"][1] - held["t_us"][0])
        for t_us in rates.bins(events):
            k = min(t_us // tick_us, len(held) - 1)
            feats.append(rates.rates.copy())
            loads.append(held["load_n"][k] if held["held"][k] else 0.0)
    x = np.asarray(feats)
    y = np.asarray(loads)
    mean_x, mean_y = x.mean(0), y.mean()
    xc = x - mean_x
    w = np.linalg.solve(xc.T @ xc + RIDGE * np.eye(x.shape[1]), xc.T @ (y - mean_y))
    return LoadReadout(w, float(mean_y - mean_x @ w), reflex.tau_s, reflex.bin_s)
