"""Typed, range-checked option values: every number the command line takes is parsed here.

Each function returns an argparse ``type=`` callable that turns the option's text into a
finite ``int`` or ``float`` inside its documented range, or refuses it with one line saying
what was expected (argparse then prints ``skinhil: error: argument --X: ...``, exit 2).
Ranges are the physical or practical limits of what the option controls; each option's
``--help`` states its range.
"""

from __future__ import annotations

import argparse
import ipaddress
import math
import os
from collections.abc import Callable

from skinhil.errors import ConfigError
from skinhil.model.geometry import MeshSize, format_size, parse_size, spring_count
from skinhil.model.neurons import check_snr_db

MAX_SEED = 2**63 - 1
"""Largest noise seed (numpy's SeedSequence takes any non-negative integer; 63 bits keep it
one machine word)."""
MAX_REST_S = 3600.0
"""Longest rest (s) after a stimulus of a random schedule (serve, train)."""
MAX_DURATION_S = 1e7
"""Longest real-time run (s: 116 days) of serve and listen."""
MAX_CHANNELS = 0xFFFF
"""Most sensor channels of a skin: the wire's event address is 16 bits (SPEC §3)."""


def integer(lo: int, hi: int, what: str = "number") -> Callable[[str], int]:
    """argparse type: an integer (decimal, or 0x.. hex) in ``lo..hi``; ``what`` names it in
    the refusal ("invalid <what> '<text>': give a whole number in lo..hi")."""

    def parse(text: str) -> int:
        try:
            value = int(text, 0)
        except ValueError:
            value = None
        if value is None or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(
                f"invalid {what} {text!r}: give a whole number in {lo}..{hi}")
        return value

    parse.__name__ = "integer"
    return parse


def real(lo: float, hi: float, unit: str, lo_open: bool = False) -> Callable[[str], float]:
    """argparse type: a finite number in ``lo..hi`` (``(lo, hi]`` when ``lo_open``), in
    ``unit``."""
    low = "more than" if lo_open else "at least"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and (value > lo if lo_open else value >= lo)
                and value <= hi):
            raise argparse.ArgumentTypeError(
                f"invalid value {text!r}: give a number of {unit}, {low} {lo:g} and at most "
                f"{hi:g}")
        return value

    parse.__name__ = "number"
    return parse


def snr_value(text: str) -> float:
    """argparse type: an SNR in dB (``MIN_SNR_DB``..``MAX_SNR_DB`` of
    :mod:`skinhil.model.neurons`), or 'inf' for no noise."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of dB (or 'inf')") from None
    try:
        return check_snr_db(value)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def cores_value(text: str) -> tuple[int, ...]:
    """argparse type: CPU cores, comma-separated, each one this process may run on."""
    allowed = sorted(os.sched_getaffinity(0))
    try:
        cores = tuple(sorted({int(part) for part in text.split(",")}))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of CPU core numbers (e.g. "
                                         f"'1' or '0,1')") from None
    wrong = [c for c in cores if c not in allowed]
    if wrong:
        raise argparse.ArgumentTypeError(
            f"core {wrong[0]} is not one this process may run on: pick from "
            f"{', '.join(map(str, allowed))}")
    return cores


def size_value(text: str) -> MeshSize:
    """argparse type: a mesh size ROWSxCOLS (>= 3x3, at most :data:`MAX_CHANNELS` sensors)."""
    try:
        size = parse_size(text)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    n = spring_count(size)
    if n > MAX_CHANNELS:
        raise argparse.ArgumentTypeError(
            f"a {format_size(size)} skin has {n} sensors; the wire addresses at most "
            f"{MAX_CHANNELS}: give a smaller size")
    return size


seed_value = integer(0, MAX_SEED, "seed")
"""argparse type: a noise seed, 0..2^63-1."""


MEMORY_SHARE = 0.8
"""Largest share of the available memory one allocation may take."""


def available_memory_bytes() -> int:
    """Memory (bytes) the system can give without swapping: MemAvailable of /proc/meminfo,
    else the physical memory."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_memory(n_bytes: int, what: str, advice: str) -> None:
    """:class:`ConfigError` (before allocating) when ``what`` needs ``n_bytes`` bytes, more
    than :data:`MEMORY_SHARE` of the available memory; ``advice`` says what to do."""
    free = available_memory_bytes()
    if n_bytes > MEMORY_SHARE * free:
        raise ConfigError(f"{what} need {n_bytes / 2**30:,.1f} GiB of memory; "
                          f"{free / 2**30:,.1f} GiB is available — {advice}")


def udp_allow_value(text: str) -> list[str]:
    """argparse type of ``--udp-allow``: comma-separated IP addresses, each optionally with
    ``:PORT`` (IPv6 with a port as ``[ADDR]:PORT``); host names are not resolved."""
    items = [item.strip() for item in text.split(",")]
    if not text.strip() or not all(items):
        raise argparse.ArgumentTypeError(f"{text!r}: give addresses such as 192.168.1.20 or "
                                         "192.168.1.20:5000, comma-separated, none empty")
    return [_udp_source(item) for item in items]


def _udp_source(item: str) -> str:
    host, port = item, ""
    if item.startswith("["):
        host, _, rest = item[1:].partition("]")
        port = rest[1:] if rest.startswith(":") else rest
    elif item.count(":") == 1:
        host, port = item.split(":")
    try:
        addr = ipaddress.ip_address(host)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{item!r} is not an IP address (host names are not resolved): give one such as "
            "192.168.1.20 or 192.168.1.20:5000") from None
    if port and not (port.isdigit() and 1 <= int(port) <= 65535):
        raise argparse.ArgumentTypeError(f"{item!r}: the port must be a number 1..65535")
    return f"{addr}:{int(port)}" if port else str(addr)
