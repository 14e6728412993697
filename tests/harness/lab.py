"""A board on a pty and ``skinhil listen`` with lab outputs (``--view``, ``--lsl``) on the
other end, both as subprocesses, as a user runs them."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from harness.host_link import linked_ptys
from harness.serve import ServeProcess

LOOPBACK_LSL_CFG = """\
[ports]
IPv6 = disable
[multicast]
ResolveScope = machine
ListenAddress = 127.0.0.1
AddressesOverride = {127.0.0.1}
[lab]
KnownPeers = {127.0.0.1}
"""
"""An lsl_api.cfg (``LSLAPICFG``) that keeps liblsl on 127.0.0.1: no IPv6, machine-scope
discovery sent to loopback."""


def quick_model(tmp_path: Path, size: tuple[int, int] = (6, 6)) -> Path:
    """A decoder for a skin of ``size`` trained in seconds (noise-free, one stimulus per
    condition)."""
    from skinhil.decoding.model_file import save_decoder
    from skinhil.receiver.training import train_decoder

    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False,
                               size=size)
    path = tmp_path / f"model-{size[0]}x{size[1]}.npz"
    save_decoder(decoder, path)
    return path


def chance_model(tmp_path: Path, size: tuple[int, int]) -> Path:
    """A decoder of the right shape for a skin of ``size`` fitted in a second on random
    features (two per direction condition): for runs whose decisions do not matter (the
    view's and the links' tests), where training on the skin would take tens of seconds."""
    import numpy as np

    from skinhil.decoding.classifier import DirectionDecoder
    from skinhil.decoding.model_file import save_decoder
    from skinhil.receiver.training import feature_spec

    spec = feature_spec(size=size)
    rng = np.random.default_rng(0)
    labels = np.repeat(np.arange(9), 2)
    decoder = DirectionDecoder(spec).fit(rng.random((labels.size, spec.n_features)), labels)
    path = tmp_path / f"chance-{size[0]}x{size[1]}.npz"
    save_decoder(decoder, path)
    return path


def wait_for_stderr(proc: ServeProcess, text: str, timeout_s: float = 60.0) -> str:
    """The first stderr line of ``proc`` that holds ``text``."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for line in list(proc.stderr_lines):
            if text in line:
                return line
        assert not proc.exited, proc.stderr
        time.sleep(0.05)
    raise AssertionError(f"no {text!r} on stderr:\n{proc.stderr}")


def stop(listen: ServeProcess, own_end_s: float = 10.0) -> None:
    """Let ``listen`` end by itself, as it does at the board's RUN_END record (status 0), for
    up to ``own_end_s``; else interrupt it (Ctrl-C): it must end cleanly, 130 with its
    summary printed. (A Ctrl-C that lands while it is already exiting would find the
    interpreter's default handler: waiting first keeps the two apart.)"""
    end = time.monotonic() + own_end_s
    while not listen.exited and time.monotonic() < end:
        time.sleep(0.05)
    expected = (0, 130) if listen.exited else (130,)
    if not listen.exited:
        listen.interrupt()
    status = listen.wait(60)
    assert status in expected, (status, listen.stderr)


@contextmanager
def listening(tmp_path: Path, *listen_args: str, ready: str) -> Iterator[
        tuple[ServeProcess, Path]]:
    """``skinhil listen --json`` on a pty with ``listen_args``, once its ready line has come
    and its stderr says ``ready`` (what a lab output announces): (the listener, the board's
    end of the pty). The listener is interrupted (and its summary collected) when the body
    ends, unless the body stopped it."""
    model = quick_model(tmp_path)
    with linked_ptys(tmp_path) as (board_end, host_end):
        listen = ServeProcess("--port", str(host_end), "--model", str(model), "--json",
                              *listen_args, command="listen")
        try:
            listen.wait_ready()
            wait_for_stderr(listen, ready)
            yield listen, board_end
            stop(listen)
        finally:
            listen.kill()
