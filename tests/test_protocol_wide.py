"""The wide format (protocol version 4, SPEC.md §9): chosen only for skins of more than 338
channels, round trips any address a stream can carry, packs its frames full, and a decoder
that does not read the version of a stream refuses it with a ProtocolError."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from protocol_examples import distinct_events
from test_protocol_roundtrip import LAYOUTS, canonical, decode_all

from protocols import CanDecoder, CanEncoder, CanFrame, SerialDecoder, SerialEncoder
from protocols import serial_kernels as k
from protocols.framing import frame_into
from protocols.versions import MAX_CHANNELS
from skinhil.errors import ProtocolError
from skinhil.events import make_events

STEP = 100
SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
WRAP_BITS = {"serial": 48, "can": 40, "canfd": 48}


def encoder(layout: str, n_channels: int, board: int = 0) -> SerialEncoder | CanEncoder:
    if layout == "serial":
        return SerialEncoder(n_channels=n_channels)
    return CanEncoder(board, fd=layout == "canfd", n_channels=n_channels)


def decoder(layout: str, versions: tuple[int, ...] = (3, 4),
            board: int = 0) -> SerialDecoder | CanDecoder:
    if layout == "serial":
        return SerialDecoder(versions=versions)
    return CanDecoder(board, fd=layout == "canfd", versions=versions)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_version_follows_the_channel_count(layout: str) -> None:
    assert encoder(layout, 1).version == encoder(layout, 338).version == 3
    assert encoder(layout, 339).version == encoder(layout, MAX_CHANNELS).version == 4
    with pytest.raises(ProtocolError, match="channels"):
        encoder(layout, MAX_CHANNELS + 1)
    with pytest.raises(ProtocolError, match="address"):
        encoder(layout, 15_730).events(make_events([0], [15_730]), 100)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_small_skin_streams_the_narrow_format_byte_for_byte(layout: str) -> None:
    ev = make_events([0, 0, 300, 900], [5, 17, 60, 2])
    small = encoder(layout, 77).events(ev, 1000)  # a 4x4 skin's channels fit 0..337
    default = SerialEncoder().events(ev, 1000) if layout == "serial" else CanEncoder(
        0, fd=layout == "canfd").events(ev, 1000)
    assert small == default


@st.composite
def wide_streams(draw: st.DrawFn, wrap_bits: int) -> tuple[int, np.ndarray, list[int]]:
    """(channels, sorted events, t_end of each call): any channel count of the wide range,
    addresses over all of it (the last included), crowded steps, silences, a wrap."""
    n_ch = draw(st.sampled_from([339, 15_730, MAX_CHANNELS]))
    start = draw(st.sampled_from([0, 777, (1 << wrap_bits) - 300]))
    t = start
    times: list[int] = []
    addrs: list[int] = []
    for i in range(draw(st.integers(1, 20))):
        if i:
            t += draw(st.one_of(st.integers(0, 20), st.integers(0, 3000),
                                st.integers(60_000, 1 << 20)))
        chans = draw(st.lists(st.one_of(st.integers(0, n_ch - 1), st.just(n_ch - 1)),
                              min_size=1, max_size=70))
        times += [t] * len(chans)
        addrs += sorted(chans)
    ends = sorted(set(draw(st.lists(st.integers(start, t), max_size=6))))
    ev = distinct_events(np.array(times, dtype=np.int64) * STEP, addrs)
    return n_ch, ev, [e * STEP for e in ends if e > start] + [(t + 1) * STEP]


@pytest.mark.parametrize("layout", LAYOUTS)
@SETTINGS
@given(data=st.data())
def test_wide_events_round_trip(layout: str, data: st.DataObject) -> None:
    n_ch, ev, ends = data.draw(wide_streams(WRAP_BITS[layout]))
    enc = encoder(layout, n_ch, board=3)
    chunks, lo = [], 0
    for end in ends:
        hi = int(np.searchsorted(ev["t"], end))
        chunks.append(enc.events(ev[lo:hi], end))
        lo = hi
    got, counters = decode_all(layout, chunks, board=3)
    np.testing.assert_array_equal(got, canonical(ev))
    assert counters.events_decoded == len(ev)
    assert counters.frames_lost == 0 and counters.events_untimed == 0


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_decoder_refuses_a_version_it_does_not_read(layout: str) -> None:
    ev = make_events([0, 100], [5, 15_000])
    wide = encoder(layout, 15_730).events(ev, 1000)
    with pytest.raises(ProtocolError, match="version 4"):
        decoder(layout, versions=(3,)).feed(wide)
    narrow = encoder(layout, 338).events(ev[:1], 1000)
    with pytest.raises(ProtocolError, match="version 3"):
        decoder(layout, versions=(4,)).feed(narrow)
    # versions 1 and 2 are retired (their serial CRC was blind to appended zeros)
    with pytest.raises(ProtocolError, match="choose among"):
        decoder(layout, versions=(1,))
    assert len(decoder(layout).feed(wide).events) == 2


def test_full_frames_and_bytes_per_event() -> None:
    """A crowded step fills every frame: 2 events per classic frame, 20 per FD frame, 3
    bytes per event word on serial."""
    ev = make_events(np.zeros(40, np.int64), np.arange(0, 40 * 300, 300))
    classic = [f for f in CanEncoder(n_channels=15_730).events(ev, 100)
               if f.arbitration_id >> 4 == 7]
    assert [len(f.data) for f in classic] == [8] * 20
    fd = [f for f in CanEncoder(fd=True, n_channels=15_730).events(ev, 100)
          if f.arbitration_id >> 4 == 7]
    assert [len(f.data) for f in fd] == [64, 64]
    one = len(SerialEncoder(n_channels=15_730).events(ev[:1], 100))
    forty = len(SerialEncoder(n_channels=15_730).events(ev, 100))
    assert 39 * 3 <= forty - one <= 39 * 3 + 1  # COBS may add one code byte


@pytest.mark.parametrize("fd", [False, True])
def test_wide_frames_are_foreign_until_a_version_2_sync(fd: bool) -> None:
    """Class 7 is another device's ID on a version-3 bus: counted foreign, never decoded."""
    frames = CanEncoder(1, fd=fd, n_channels=15_730).events(make_events([0], [9000]), 100)
    sync, wide = frames
    dec = CanDecoder(1, fd=fd)
    assert len(dec.feed([wide]).events) == 0 and dec.counters.foreign_frames == 1
    got = dec.feed([sync, wide]).events
    assert got["addr"].tolist() == [9000] and dec.counters.foreign_frames == 1


def test_wide_serial_address_beyond_the_range_is_malformed() -> None:
    """An all-ones (or out of range) address is a layout error, counted, never returned."""
    enc = SerialEncoder(n_channels=MAX_CHANNELS)
    dec = SerialDecoder()
    assert dec.feed(enc.events(make_events([0], [MAX_CHANNELS - 1]), 100)).events[
        "addr"].tolist() == [MAX_CHANNELS - 1]

    body = np.zeros(16, np.uint8)
    body[:4] = [(k.T_WIDE << 5) | 0, 2, 0, 0]
    body[4:7] = np.frombuffer(((0xFFFFF << 4) | 1).to_bytes(3, "little"), np.uint8)
    out = np.zeros(32, np.uint8)
    n = frame_into(body, 7, out, 0)
    dec.feed(out[:n].tobytes())
    assert dec.counters.malformed == 1 and dec.counters.events_decoded == 1


@pytest.mark.parametrize("layout", LAYOUTS)
@settings(max_examples=60, deadline=None, derandomize=True)
@given(junk=st.lists(st.binary(max_size=64), max_size=60), ids=st.lists(
    st.integers(0, 0x7FF), min_size=60, max_size=60))
def test_wide_decoders_never_raise_on_garbage(layout: str, junk: list[bytes],
                                              ids: list[int]) -> None:
    """After a version-4 SYNC, random bytes or frames (wide class included) never raise."""
    enc = encoder(layout, 15_730)
    dec = decoder(layout)
    dec.feed(enc.events(make_events([0], [1]), 100))
    if layout == "serial":
        res = dec.feed(b"".join(junk))
    else:
        res = dec.feed([CanFrame(i, d[:64 if layout == "canfd" else 8], layout == "canfd")
                        for i, d in zip(ids, junk, strict=False)])
    assert len(res.events) == dec.counters.events_decoded - 1
