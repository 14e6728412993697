"""Lab Streaming Layer (LSL) outlets of a received stream, with pylsl.

``skinhil listen --lsl [NAME]`` publishes the spikes, the PSP traces, the ground-truth
markers, the decisions and the link's health as LSL streams stamped on LSL's clock, so
LabRecorder and the LSL apps record them beside EMG, motion or video. pylsl (its wheel ships
liblsl) is an optional dependency: ``pip install "skinhil[lsl]"``.
"""

from skinhil.lsl.outlets import LINK_CHANNELS, LslOutlets, require_pylsl

__all__ = ["LINK_CHANNELS", "LslOutlets", "require_pylsl"]
