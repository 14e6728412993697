"""Recording and replaying sessions.

- What a board puts on its link, as it goes (``serve --record FILE``):
  :func:`link_recorder` and :class:`RecordingTransport`; CAN in python-can's log formats,
  serial and UDP in the capture format of SPEC.md "Capture files" (:mod:`protocols.capture`),
  chosen by the file's extension (:func:`recording_format`).
- Playing it back onto a link (``serve --replay FILE``): :func:`open_recording`,
  :class:`Replayer`.
- What a receiver decoded (``listen --record``, .npz; .nwb through :mod:`skinhil.nwb`):
  :class:`SessionRecorder`, streamed to disk.
"""

from __future__ import annotations

from skinhil.recording.formats import CAPTURE_SUFFIX, check_link_fits, recording_format
from skinhil.recording.link_recorder import LinkRecorder, RecordingTransport, link_recorder
from skinhil.recording.recordings import Recording, open_recording
from skinhil.recording.replay import Replayer, ReplaySummary
from skinhil.recording.session import DECISION_DTYPE, MARKER_DTYPE, SessionRecorder

__all__ = [
    "CAPTURE_SUFFIX", "DECISION_DTYPE", "MARKER_DTYPE", "LinkRecorder", "Recording",
    "RecordingTransport", "ReplaySummary", "Replayer", "SessionRecorder", "check_link_fits",
    "link_recorder", "open_recording", "recording_format",
]
