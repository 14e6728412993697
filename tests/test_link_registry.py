"""Links as a registry of URL schemes (docs/links.md): the built-in links come from the
``skinhil.links`` entry points, each URL opens and writes itself back, bad URLs are refused
in one line naming what to give, and a link written in this file alone, installed as a
package in a temporary folder, carries a whole ``skinhil serve`` -> ``skinhil listen``
session."""

from __future__ import annotations

import json
import math
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

import pytest
from harness.serve import RUN_DIR, serve_env

import protocols
from skinhil.decoding.model_file import save_decoder
from skinhil.errors import TransportError
from skinhil.receiver.training import train_decoder
from skinhil.transports import Transport, link_class, link_schemes, open_link, register_link

BUILT_IN = {"serial": "SerialTransport", "can": "CanTransport", "udp": "UdpTransport",
            "pty": "PtyMasterTransport"}


@pytest.mark.parametrize("scheme", sorted(BUILT_IN))
def test_built_in_links_are_the_entry_points(scheme: str) -> None:
    (ep,) = entry_points(group="skinhil.links", name=scheme)
    cls = ep.load()
    assert issubclass(cls, Transport) and cls.__name__ == BUILT_IN[scheme]
    assert cls.scheme == scheme
    assert link_class(scheme) is cls
    assert scheme in link_schemes()


def _virtual() -> str:
    return f"registry-{random.getrandbits(32)}"


@pytest.mark.parametrize("url, role, frames, fd, unit", [
    ("serial:loop://?baud=115200", "board", False, False, "bytes"),
    ("pty:?baud=9600", "board", False, False, "bytes"),
    ("udp:127.0.0.1:0?bitrate=2000000", "host", False, False, "bytes"),
    ("can:{chan}?interface=virtual&fd=1&bitrate=500000&data_bitrate=2000000", "board", True,
     True, "frames"),
    ("can:{chan}?interface=virtual&fd=0&bitrate=1000000", "host", True, False, "frames"),
])
def test_url_round_trip(url: str, role: Any, frames: bool, fd: bool, unit: str) -> None:
    """A URL opens its link, whose properties say what it carries, and whose ``url`` opens
    the same link again."""
    url = url.format(chan=_virtual())
    with open_link(url, role) as link:
        assert (link.carries_frames, link.can_fd, link.unit) == (frames, fd, unit)
        again_url = link.url
        if link.scheme != "udp":  # a UDP host's port 0 becomes the port it bound
            assert again_url == url
        encoder, decoder = link.codec_pair(board_id=3)
        sent = encoder.ack(protocols.Ack(token=7, opcode=1, ok=True, reason=0))
        assert isinstance(sent, list) == frames
        assert [r.token for r in decoder.feed(sent).records] == [7]
        if link.scheme == "udp":
            with open_link(again_url, "board") as board:
                assert board.send(b"\x01\x00") == 2
                assert link.recv(timeout=2.0) == b"\x01\x00"
            return
    with open_link(again_url, role) as again:
        assert again.url == again_url


def test_udp_shorthand_host_listens_on_loopback() -> None:
    with open_link("udp:0", "host") as link:
        assert link.url.startswith("udp:127.0.0.1:") and link.whole_datagrams


@pytest.mark.parametrize("url, names", [
    ("ttyUSB0", "SCHEME:TARGET"),
    ("nosuch:x", "serial:"),
    ("serial:", "serial:/dev/ttyUSB0"),
    ("serial:loop://?baud=fast", "baud="),
    ("serial:loop://?speed=9600", "baud"),
    ("serial:loop://?baud=1&baud=2", "once"),
    ("can:vcan0?fd=maybe", "fd=1"),
    ("can:?interface=virtual", "can:vcan0"),
    ("udp:9000", "HOST:PORT"),
    ("udp:127.0.0.1:70000", "0..65535"),
    ("pty:/dev/pts/3", "pty:"),
])
def test_bad_urls_are_refused_in_one_line(url: str, names: str) -> None:
    with pytest.raises(TransportError) as err:
        open_link(url, "board")
    message = str(err.value)
    assert "\n" not in message and names in message, message
    assert any(word in message for word in ("give", "e.g.", "write")), message


class _Loopback(Transport[bytes]):
    """An in-process loopback: what is sent is received."""

    scheme = "loopback"

    def __init__(self) -> None:
        self.buf = b""

    @classmethod
    def from_url(cls, url: Any, role: Any) -> _Loopback:
        url.check_options(())
        return cls()

    @property
    def name(self) -> str:
        return "loopback"

    def send(self, payload: bytes, timeout: float | None = None) -> int:
        self.buf += payload
        return len(payload)

    def recv(self, timeout: float | None = None) -> bytes:
        out, self.buf = self.buf, b""
        return out

    def wire_seconds(self, payload: bytes) -> float:
        return len(payload) * 1e-7

    def empty(self) -> bytes:
        return b""

    def shutdown(self) -> None:
        pass


def test_a_link_registered_in_process_opens_and_carries_the_protocol() -> None:
    register_link("loopback", _Loopback)
    with open_link("loopback:", "board") as link:
        encoder, decoder = link.codec_pair()
        link.send(encoder.command(protocols.Command(5, protocols.CommandCode.PING)))
        assert [r.token for r in decoder.feed(link.recv(0)).records] == [5]
    with pytest.raises(TransportError, match="unknown option"):
        open_link("loopback:?x=1")
    with pytest.raises(TransportError, match="Transport"):
        register_link("notalink", dict)  # type: ignore[arg-type]


UNIX_LINK = textwrap.dedent('''
    """A serial byte stream over a Unix stream socket: ``unixsock:PATH?baud=N``. The host
    binds PATH and accepts the board, which connects to it."""

    import os
    import select
    import socket

    from skinhil.errors import TransportError
    from skinhil.transports import Transport


    class UnixSocketLink(Transport):
        kind = "serial"
        scheme = "unixsock"

        def __init__(self, path, host, baud):
            self.path, self.host, self.baud = path, host, baud
            self.conn = None
            if host:
                self.server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                self.server.bind(path)
                self.server.listen(1)
            else:
                self.server = None
                self.conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                try:
                    self.conn.connect(path)
                except OSError as exc:
                    raise TransportError(f"nobody listens on {path}: {exc}") from None
                self.conn.setblocking(False)

        @classmethod
        def from_url(cls, url, role):
            url.check_options(("baud",))
            return cls(url.require_target("unixsock:/tmp/link.sock"), role == "host",
                       url.int_option("baud", 921600))

        @property
        def name(self):
            return f"unix socket {self.path}"

        @property
        def url(self):
            return f"unixsock:{self.path}?baud={self.baud}"

        def _accept(self, timeout):
            if self.conn is None:
                ready, _, _ = select.select([self.server], [], [], timeout)
                if ready:
                    self.conn, _ = self.server.accept()
                    self.conn.setblocking(False)
            return self.conn

        def send(self, payload, timeout=None):
            conn = self._accept(0)
            if conn is None or not payload:
                return 0
            try:
                return conn.send(payload)
            except BlockingIOError:
                return 0

        def recv(self, timeout=None):
            conn = self._accept(timeout)
            if conn is None:
                return b""
            ready, _, _ = select.select([conn], [], [], timeout)
            if not ready:
                return b""
            try:
                return conn.recv(65536)
            except BlockingIOError:
                return b""

        def wire_seconds(self, payload):
            return 10 * len(payload) / self.baud

        def empty(self):
            return b""

        def shutdown(self):
            for s in (self.conn, self.server):
                if s is not None:
                    s.close()
            self.conn = self.server = None
            if self.host and os.path.exists(self.path):
                os.unlink(self.path)
''')


def _install_link_package(root: Path) -> None:
    """Write the link's module and a dist-info registering it under ``skinhil.links``."""
    (root / "unixsock_link.py").write_text(UNIX_LINK)
    info = root / "unixsock_link-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: unixsock-link\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[skinhil.links]\nunixsock = unixsock_link:UnixSocketLink\n")


def test_a_link_from_outside_the_package_carries_a_serve_listen_session(
        tmp_path: Path) -> None:
    site = tmp_path / "site"
    site.mkdir()
    _install_link_package(site)
    decoder, _ = train_decoder(math.inf, reps=1, seed=0, rest_s=0.05, cross_validation=False)
    model = tmp_path / "model.npz"
    save_decoder(decoder, model)
    sock = tmp_path / "link.sock"
    env = serve_env()
    env["PYTHONPATH"] = os.pathsep.join([str(site), env["PYTHONPATH"]])
    url = f"unixsock:{sock}?baud=921600"
    listen = subprocess.Popen(
        [sys.executable, "-m", "skinhil", "listen", "--link", url, "--model", str(model),
         "--json"], cwd=RUN_DIR, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL, text=True)
    try:
        end = time.monotonic() + 120
        while not sock.exists():
            assert listen.poll() is None and time.monotonic() < end, listen.communicate()
            time.sleep(0.05)
        serve = subprocess.run(
            [sys.executable, "-m", "skinhil", "serve", "--link", url, "--duration", "1.0",
             "--json"], cwd=RUN_DIR, env=env, capture_output=True, text=True, timeout=180,
            stdin=subprocess.DEVNULL)
        assert serve.returncode == 0, serve.stderr
        try:
            out, err = listen.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            listen.send_signal(signal.SIGINT)
            out, err = listen.communicate(timeout=30)
    finally:
        if listen.poll() is None:
            listen.kill()
    summaries = [json.loads(line) for line in out.splitlines() if '"summary"' in line]
    assert summaries, err
    summary = summaries[-1]
    board = [json.loads(line) for line in serve.stdout.splitlines() if '"summary"' in line][-1]
    assert summary["run_end"] is not None, summary
    assert summary["link"]["events_decoded"] == board["sent"] > 0
