"""skinhil: real-time neuromorphic hardware-in-the-loop emulator of touch.

The model (skin mechanics → spring forces → noisy Izhikevich neurons → spikes → PSP) is
importable from here; see the submodules for the equations.
"""

# isort: off
import protocols.kernel_cache  # noqa: F401  (keys numba's cache on the sources: first of all)
# isort: on
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
from skinhil.model.skin import SkinModel, SkinParams, SkinStepper
from skinhil.model.stimuli import (
    Schedule,
    ScheduledStimulus,
    Stimulus,
    at_size,
    direction_conditions,
    load_schedule,
    paper_stimuli,
    random_schedule,
)
from skinhil.model.trials import simulate_trial_events, simulate_trials

__version__ = "0.1.0"

__all__ = [
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
