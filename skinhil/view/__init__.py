"""The live view: a local web page of a received stream, updated 10 times a second.

``skinhil listen --view [HOST:]PORT`` (and ``skinhil demo --view``) serves, on 127.0.0.1
unless told otherwise, a scrolling raster of every channel (channels on y, board time on
x, as Open Ephys and SpikeGLX draw them), the PSP traces of chosen sensors, each decision
beside its ground truth with the running confusion matrix, and the link and board
counters; with a held object (``demo --task grasp --view``) a panel plots its grip, load
and slip over board time, from the board's truth. It needs nothing beyond the standard
library: the server is
:class:`http.server.ThreadingHTTPServer` with server-sent events, the page plain
JavaScript on canvases, its assets package data (it works offline).
"""

from skinhil.view.feed import ViewFeed
from skinhil.view.server import ViewServer, parse_address

__all__ = ["ViewFeed", "ViewServer", "parse_address"]
