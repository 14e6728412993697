"""The live view's web server: the page, its assets and the update stream (SSE).

The standard library's :class:`http.server.ThreadingHTTPServer` with server-sent events
(``text/event-stream``): the updates flow one way, server → page, which is what SSE is
for; the browser's ``EventSource`` reconnects by itself; no dependency is installed for it
and nothing leaves the machine (it binds 127.0.0.1 unless told otherwise). A WebSocket
server would add a dependency (or a hand-written framing) for a back channel the view does
not need. Each page has its own thread and a short queue: a slow page loses its oldest
updates (counted in ``/client``), never slows the receiver.

Paths: ``/`` the page, ``/view.js`` and ``/view.css`` its assets (package data, no CDN),
``/events`` the stream (a ``config`` event, then an ``update`` event every
``period_s``), ``/client`` (GET) what the pages reported: their own errors and what they
drew (POSTed by the page to ``/client``), for tests and for ``--json`` users.
"""

from __future__ import annotations

import json
import logging
import queue
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

from skinhil.errors import ConfigError, TransportError
from skinhil.transports.udp import parse_address as socket_address
from skinhil.view.feed import ViewFeed

log = logging.getLogger(__name__)

UPDATE_PERIOD_S = 0.1
"""Seconds between updates (10 Hz)."""

QUEUE_UPDATES = 20
"""Updates a page may fall behind before its oldest are dropped."""

ASSETS = {"/": ("index.html", "text/html; charset=utf-8"),
          "/index.html": ("index.html", "text/html; charset=utf-8"),
          "/view.js": ("view.js", "text/javascript; charset=utf-8"),
          "/view.css": ("view.css", "text/css; charset=utf-8")}


def parse_address(text: str) -> tuple[str, int]:
    """``[HOST:]PORT`` → (host, port); the host is 127.0.0.1 unless given (the UDP link's
    address rule)."""
    try:
        return socket_address(text, "127.0.0.1")
    except TransportError:
        raise ConfigError(f"--view {text!r}: give [HOST:]PORT, e.g. 8050 or 0.0.0.0:8050 "
                          "(port 0: any free port)") from None


def _asset(name: str) -> bytes:
    return resources.files("skinhil.view").joinpath("static", name).read_bytes()


class ViewServer:
    """Serve the view of ``feed`` at ``host:port`` (port 0: any free port) on threads."""

    def __init__(self, feed: ViewFeed, host: str = "127.0.0.1", port: int = 0,
                 period_s: float = UPDATE_PERIOD_S) -> None:
        self.feed = feed
        self.period_s = float(period_s)
        self._clients: list[queue.Queue[str]] = []
        self._clients_lock = threading.Lock()
        self.client_reports: dict[str, Any] = {"errors": [], "state": None, "dropped": 0}
        self._stop = threading.Event()
        try:
            self.httpd = ThreadingHTTPServer((host, port), self._handler())
        except OSError as exc:
            raise ConfigError(f"--view cannot listen on {host}:{port}: {exc.strerror} — "
                              "choose another port") from None
        self.httpd.daemon_threads = True
        self._threads = [threading.Thread(target=self.httpd.serve_forever, name="skinhil-view",
                                          daemon=True),
                         threading.Thread(target=self._publish, name="skinhil-view-updates",
                                          daemon=True)]

    @property
    def url(self) -> str:
        """The page's address."""
        host, port = self.httpd.server_address[:2]
        name = host.decode() if isinstance(host, bytes) else str(host)
        return f"http://{name}:{port}/"

    def start(self) -> ViewServer:
        for t in self._threads:
            t.start()
        log.info("live view at %s", self.url)
        return self

    def close(self) -> None:
        """Stop serving (pages see the stream end)."""
        self._stop.set()
        self.httpd.shutdown()
        self.httpd.server_close()
        for t in self._threads:
            t.join(timeout=2.0)

    def _publish(self) -> None:
        next_t = time.monotonic()
        while not self._stop.is_set():
            next_t += self.period_s
            self._stop.wait(max(0.0, next_t - time.monotonic()))
            msg = self.feed.update()
            with self._clients_lock:
                clients = list(self._clients)
            if not clients:
                continue
            text = json.dumps(msg, separators=(",", ":"))
            for q in clients:
                while True:
                    try:
                        q.put_nowait(text)
                        break
                    except queue.Full:
                        try:
                            q.get_nowait()
                            self.client_reports["dropped"] += 1
                        except queue.Empty:
                            pass

    def _stream(self, handler: BaseHTTPRequestHandler) -> None:
        q: queue.Queue[str] = queue.Queue(maxsize=QUEUE_UPDATES)
        handler.send_response(HTTPStatus.OK)
        handler.send_header("Content-Type", "text/event-stream")
        handler.send_header("Cache-Control", "no-cache")
        handler.end_headers()
        with self._clients_lock:
            self._clients.append(q)
        try:
            config = json.dumps(self.feed.hello(), separators=(",", ":"))
            handler.wfile.write(f"event: config\ndata: {config}\n\n".encode())
            handler.wfile.flush()
            while not self._stop.is_set():
                try:
                    text = q.get(timeout=1.0)
                except queue.Empty:
                    handler.wfile.write(b": alive\n\n")
                else:
                    handler.wfile.write(f"event: update\ndata: {text}\n\n".encode())
                handler.wfile.flush()
        except (BrokenPipeError, ConnectionResetError):
            pass
        finally:
            with self._clients_lock:
                self._clients.remove(q)

    def _report(self, body: bytes) -> None:
        try:
            report = json.loads(body or b"{}")
        except json.JSONDecodeError:
            return
        if report.get("kind") == "error":
            message = str(report.get("message", ""))[:2000]
            self.client_reports["errors"].append(message)
            log.warning("the live view page reported an error: %s", message)
        elif report.get("kind") == "state":
            self.client_reports["state"] = report

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        server = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, format: str, *args: Any) -> None:
                log.debug("view: " + format, *args)

            def _send(self, body: bytes, content_type: str,
                      status: HTTPStatus = HTTPStatus.OK) -> None:
                self.send_response(status)
                self.send_header("Content-Type", content_type)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-cache")
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self) -> None:  # noqa: N802 (the stdlib's name)
                path = self.path.split("?", 1)[0]
                if path == "/events":
                    server._stream(self)
                    self.close_connection = True
                elif path == "/client":
                    self._send(json.dumps(server.client_reports).encode(),
                               "application/json")
                elif path in ASSETS:
                    name, kind = ASSETS[path]
                    self._send(_asset(name), kind)
                elif path == "/favicon.ico":
                    self._send(b"", "image/x-icon", HTTPStatus.NO_CONTENT)
                else:
                    self._send(b"not found", "text/plain", HTTPStatus.NOT_FOUND)

            def do_POST(self) -> None:  # noqa: N802
                length = min(int(self.headers.get("Content-Length") or 0), 1 << 16)
                body = self.rfile.read(length)
                if self.path.split("?", 1)[0] == "/client":
                    server._report(body)
                self._send(b"", "text/plain", HTTPStatus.NO_CONTENT)

        return Handler
