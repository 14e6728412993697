"""NWB (Neurodata Without Borders) files of skinhil's spikes, stimuli and forces, with pynwb.

The field's file format for spikes and stimuli: one *unit* per sensor (its spike times in s,
with the spring's metadata: index, the two masses it joins, its layer and rest length), the
stimuli as the file's *trials* (onset, end, stimulus id and name, the peak force vector on
each pushed mass as text, its magnitude in N and in-plane angle in degrees) and, for a
simulation, the spring forces as an acquisition ``TimeSeries`` (N, one column per spring, at
the simulation step). pynwb is an optional dependency: ``pip install "skinhil[nwb]"``.
"""

from skinhil.nwb.session import write_session
from skinhil.nwb.simulation import require_pynwb, write_simulation

__all__ = ["require_pynwb", "write_session", "write_simulation"]
