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
from skinhil.world import Scene, TouchSensor

TRAINING_GRIPS_N = (0.8, 1.0, 1.2)
"""Constant grips of the default object's training lifts (N): each holds it."""
SUITE_TRAINING_GRIPS_N = (0.5, 0.9, 1.3, 1.7)
"""Constant grips of a suite's training lifts (N): from sparing the fragile objects to
holding the sturdy ones (tactile-v1:grasp), so that the readout sees every load at several
grips and tells the load's share of the rates from the grip's."""
RIDGE = 3e4
"""Ridge penalty (spikes²/s², the squared rates' scale) of the fit."""


def simulate_lifts(grip_n: float, lifts: int, snr_db: float, seed: int,
                   params: GraspParams | None = None, size: MeshSize = PAPER_SIZE,
                   dt_s: float = 1e-4, tick_s: float = 1e-3
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``lifts`` lifts of the default object at a constant grip: the events (EVENT_DTYPE,
    board time) and the held object's truth (:data:`skinhil.plant.HELD_DTYPE`, one row per
    tick)."""
    params = params or GraspParams()
    return simulate_scene(lift_scene(params, lifts), lifts * params.period_s, grip_n,
                          snr_db, seed, params, size, dt_s, tick_s)


def simulate_scene(scene: Scene, duration_s: float, grip_n: float, snr_db: float, seed: int,
                   params: GraspParams, size: MeshSize = PAPER_SIZE, dt_s: float = 1e-4,
                   tick_s: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """The lifts of ``scene`` (a suite case's, each its own object) for ``duration_s`` at a
    constant grip (N): events and held-object truth as :func:`simulate_lifts`'."""
    sensor = SkinSensor(SkinModel(SkinParams(size=size)), dt_s, snr_db, seed,
                        state_forces=True)
    touch = TouchSensor(sensor, scene)
    steps = int(round(tick_s / dt_s))
    plant = HeldObject(params, touch.world, int(round(tick_s * 1e6)))
    plant.grip_n = grip_n
    touch.start(0.0)
    empty = Schedule(())
    events, rows = [], []
    for k in range(int(round(duration_s / tick_s))):
        plant.before_tick()
        _, spikes, raw = touch.advance_schedule(empty, steps)
        rows.append(plant.after_tick(int(round(k * tick_s * 1e6)), k * tick_s, dt_s, raw))
        events.append(sensor.events(spikes, k * steps))
    return np.concatenate(events), np.concatenate(rows)


TrainingLifts = tuple[Scene, float, GraspParams]
"""A run of lifts to fit on: its scene (each lift its own object), its duration (s) and the
hand's phases."""


def fit_readout(snr_db: float, seed: int = 0, lifts: int = 2,
                reflex: ReflexParams | None = None, params: GraspParams | None = None,
                size: MeshSize = PAPER_SIZE, runs: tuple[TrainingLifts, ...] = (),
                grips_n: tuple[float, ...] = TRAINING_GRIPS_N) -> LoadReadout:
    """The load readout fitted on ``runs`` (a suite's training lifts, drawn by the caller
    from its training seeds), each at every grip of ``grips_n``; with no ``runs``, on
    ``lifts`` lifts of the default object. The grip held is a regressor beside the rates
    (:class:`LoadReadout`'s efference copy), fitted without penalty."""
    reflex = reflex or ReflexParams()
    params = params or GraspParams()
    todo = runs or ((lift_scene(params, lifts), lifts * params.period_s, params),)
    n_channels = SkinModel(SkinParams(size=size)).n_springs
    feats, loads = [], []
    for r, (scene, duration_s, run_params) in enumerate(todo):
        for i, grip in enumerate(grips_n):
            events, held = simulate_scene(scene, duration_s, grip, snr_db,
                                          seed + r * len(grips_n) + i, run_params, size)
            rates = ChannelRates(n_channels, reflex.bin_s, reflex.tau_s)
            tick_us = int(held["t_us"][1] - held["t_us"][0])
            for t_us in rates.bins(events):
                k = min(t_us // tick_us, len(held) - 1)
                feats.append(np.append(rates.rates, grip))
                loads.append(held["load_n"][k] if held["held"][k] else 0.0)
    x = np.asarray(feats)
    y = np.asarray(loads)
    mean_x, mean_y = x.mean(0), y.mean()
    xc = x - mean_x
    penalty = RIDGE * np.eye(x.shape[1])
    penalty[-1, -1] = 0.0  # the grip's weight is not shrunk
    w = np.linalg.solve(xc.T @ xc + penalty, xc.T @ (y - mean_y))
    return LoadReadout(w[:-1], float(mean_y - mean_x @ w), reflex.tau_s, reflex.bin_s,
                       float(w[-1]))
