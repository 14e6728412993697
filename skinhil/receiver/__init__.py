"""The reference receiver: decode a board's stream, PSP-filter it, classify online.

See ``docs/receiver.md`` for the pipeline, the onset rule and the measured figures.
"""

from skinhil.receiver.answer import DecisionAnswerer
from skinhil.receiver.bus import BusReceiver
from skinhil.receiver.clock import BoardClock
from skinhil.receiver.decoder_adapter import WindowDecoder
from skinhil.receiver.online import OnlineClassifier, Prediction
from skinhil.receiver.onset import OnsetDetector
from skinhil.receiver.params import OnsetParams, ReceiverParams
from skinhil.receiver.receiver import LinkReport, Receiver, ReceiverListener, in_stream_order
from skinhil.receiver.scoring import Scoreboard, ScoredDecision

__all__ = [
    "BoardClock",
    "BusReceiver",
    "DecisionAnswerer",
    "LinkReport",
    "OnlineClassifier",
    "OnsetDetector",
    "OnsetParams",
    "Prediction",
    "Receiver",
    "ReceiverListener",
    "ReceiverParams",
    "Scoreboard",
    "ScoredDecision",
    "WindowDecoder",
    "in_stream_order",
]
