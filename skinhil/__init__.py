"""skinhil: real-time neuromorphic hardware-in-the-loop emulator of touch.

The model (skin mechanics → spring forces → noisy Izhikevich neurons → spikes → PSP) is
importable from here; see the submodules for the equations. :class:`Board` and
:class:`Receiver` are the notebook API (:mod:`skinhil.api`, docs/api.md): a board running
in real time over a link and a receiver of its stream.

The names below are imported on first use (PEP 562): ``import skinhil`` alone loads neither
numpy nor numba, so the command line can install its signal handlers first of all
(:mod:`skinhil.cli.signals`). :mod:`skinhil.model` configures numba's kernel cache
(:mod:`protocols.kernel_cache`) before it defines a kernel.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from skinhil.api import Board, Receiver
    from skinhil.events import EVENT_DTYPE, make_events
    from skinhil.model.neurons import (
        IzhikevichParams,
        NeuronPopulation,
        NoiseParams,
        events_to_raster,
        raster_to_events,
        simulate_spikes,
    )
    from skinhil.model.psp import PSPFilterBank, PSPParams, psp_kernel
    from skinhil.model.schedule_file import load_schedule
    from skinhil.model.skin import SkinModel, SkinParams, SkinStepper
    from skinhil.model.stimuli import (
        Schedule,
        ScheduledStimulus,
        Stimulus,
        at_size,
        direction_conditions,
        paper_stimuli,
        random_schedule,
    )
    from skinhil.model.trials import simulate_trial_events, simulate_trials

_EXPORTS: dict[str, str] = {
    "Board": "skinhil.api",
    "Receiver": "skinhil.api",
    "EVENT_DTYPE": "skinhil.events",
    "IzhikevichParams": "skinhil.model.neurons",
    "NeuronPopulation": "skinhil.model.neurons",
    "NoiseParams": "skinhil.model.neurons",
    "PSPFilterBank": "skinhil.model.psp",
    "PSPParams": "skinhil.model.psp",
    "Schedule": "skinhil.model.stimuli",
    "ScheduledStimulus": "skinhil.model.stimuli",
    "SkinModel": "skinhil.model.skin",
    "SkinParams": "skinhil.model.skin",
    "SkinStepper": "skinhil.model.skin",
    "Stimulus": "skinhil.model.stimuli",
    "at_size": "skinhil.model.stimuli",
    "direction_conditions": "skinhil.model.stimuli",
    "events_to_raster": "skinhil.model.neurons",
    "load_schedule": "skinhil.model.schedule_file",
    "make_events": "skinhil.events",
    "paper_stimuli": "skinhil.model.stimuli",
    "psp_kernel": "skinhil.model.psp",
    "random_schedule": "skinhil.model.stimuli",
    "raster_to_events": "skinhil.model.neurons",
    "simulate_spikes": "skinhil.model.neurons",
    "simulate_trial_events": "skinhil.model.trials",
    "simulate_trials": "skinhil.model.trials",
}
"""Where each public name lives."""


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'skinhil' has no attribute {name!r}")


__version__ = "0.1.0"

__all__ = [
    "Board",
    "Receiver",
    "EVENT_DTYPE",
    "IzhikevichParams",
    "NeuronPopulation",
    "NoiseParams",
    "PSPFilterBank",
    "PSPParams",
    "Schedule",
    "ScheduledStimulus",
    "SkinModel",
    "SkinParams",
    "SkinStepper",
    "Stimulus",
    "at_size",
    "direction_conditions",
    "events_to_raster",
    "load_schedule",
    "make_events",
    "paper_stimuli",
    "psp_kernel",
    "random_schedule",
    "raster_to_events",
    "simulate_spikes",
    "simulate_trial_events",
    "simulate_trials",
]
