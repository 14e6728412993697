"""Running every encode and decode path once, off the clock, so no kernel compiles inside
a real-time loop."""

from __future__ import annotations

from typing import Any

import numpy as np

from protocols.events import make_events
from protocols.records import (
    Ack,
    Command,
    CommandCode,
    Marker,
    MarkerPhase,
    NackReason,
    RunEnd,
    RunEndReason,
)


def exercise_codecs(encoder: Any, decoder: Any, step_us: int, status: Any) -> list[Any]:
    """Encode a status, one-event and several-event blocks, an idle span, markers, an ACK,
    a command and a session record with fresh ``encoder``, decode them all with fresh
    ``decoder``; return the payloads.

    The protocol kernels are compiled (or loaded from numba's cache) on first use: that
    takes milliseconds from a warm cache and about a second from a cold one, so it must
    never happen inside a tick (the first status, marker, ACK, event block or host command
    would stall the board). The board and a replay call this before their clock starts;
    the UML test runner calls it on the host so the cache is warm before booting.
    """
    t = np.array([0, step_us, step_us, 70 * step_us, 5000 * step_us], dtype=np.int64)
    last = int(encoder.n_channels) - 1  # addresses of any skin >= 3x3 (at least 3 channels)
    ev = make_events(t, np.array([0, 1, last, last // 2, min(5, last)]))
    # a one-event block is a distinct compiled signature (its field view is contiguous)
    out = [encoder.status(status), encoder.events(ev[:1], step_us),
           encoder.events(ev[1:], int(t[-1]) + step_us),
           encoder.events(ev[:0], int(t[-1]) + 400_000),
           encoder.marker(Marker(t_us=0, stimulus_id=0, phase=MarkerPhase.ONSET)),
           encoder.marker(Marker(t_us=step_us, stimulus_id=1, phase=MarkerPhase.END)),
           encoder.ack(Ack(token=1, opcode=CommandCode.PING, ok=True,
                           reason=NackReason.NONE)),
           encoder.command(Command(token=1, opcode=CommandCode.SET_SNR, arg=20.0)),
           encoder.session_record(RunEnd(t_us=0, reason=RunEndReason.DURATION))]
    for payload in out:
        decoder.feed(payload)
    return out
