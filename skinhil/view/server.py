"""The live view's web server: the page, its assets and the update stream (SSE).

The standard library's :class:`http.server.ThreadingHTTPServer` with server-sent events
(``text/event-stream``): the updates flow one way, server → page, which is what SSE is
for; the browser's ``EventSource`` reconnects by itself; no dependency is installed for it
and nothing leaves the machine (it binds 127.0.0.1 unless told otherwise). A WebSocket
server would add a dependency (or a hand-written framing) for a back channel the view does
not need. Each page has its own thread and a short queue: a slow page loses its oldest
updates (counted in ``/client``), never slows the receiver.

Paths: ``/`` the page, ``/view.js`` and ``/view.css`` its assets (package data, no CDN),
``/events`` the stream (a ``config`` event, then an ``update`` event every ``period_s``,
and an ``end`` event when the server closes: the page then shows the run ended instead of
reconnecting), ``/events?board=KEY`` the stream of one board where several send
(``listen --udp``; the config and every update list them all in ``boards``), ``/psp`` (POST
``{"board": KEY, "sensors": [...]}``) the PSP sensors a page picked, ``/client`` (GET)
what the pages reported: their own errors and what they drew (POSTed by the page to
``/client``), for tests and for ``--json`` users.
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
from urllib.parse import parse_qs, urlsplit

from skinhil.errors import ConfigError, TransportError
from skinhil.transports.udp import parse_address as socket_address
from skinhil.view.feed import ViewFeed

log = logging.getLogger(__name__)

UPDATE_PERIOD_S = 0.1
"""Seconds between updates (10 Hz)."""

QUEUE_UPDATES = 20
"""Updates a page may fall behind before its oldest are dropped."""

END = "\x00end"
"""A page's queue item that ends its stream (the server closes)."""

END_FLUSH_S = 1.0
"""Seconds :meth:`ViewServer.close` gives the pages to get the last update and the end."""

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


KEPT_ERRORS = 100
"""Page error reports kept for ``GET /client`` (the rest only counted)."""
LOGGED_ERRORS = 10
"""Page error reports logged as WARNING lines (the rest only counted)."""
MAX_REPORT_BYTES = 1 << 16
"""Largest report body read (bytes); a longer one is refused unread."""


class _QuietHTTPServer(ThreadingHTTPServer):
    """A request that fails (a client gone, a malformed request) is logged at DEBUG, not
    printed as a traceback on the command's terminal."""

    def handle_error(self, request: Any, client_address: Any) -> None:
        log.debug("view: request from %s failed", client_address, exc_info=True)


class ViewServer:
    """Serve the view of ``feed`` at ``host:port`` (port 0: any free port) on threads;
    further boards' feeds join with :meth:`add_feed` (several boards on one link)."""

    def __init__(self, feed: ViewFeed | None, host: str = "127.0.0.1", port: int = 0,
                 period_s: float = UPDATE_PERIOD_S) -> None:
        self.feeds: dict[str, ViewFeed] = {}
        """Each board's feed by its key (the first board's is ``"0"`` with one board)."""
        self.period_s = float(period_s)
        self._clients: list[tuple[str, queue.Queue[str]]] = []
        self._clients_lock = threading.Lock()
        self.client_reports: dict[str, Any] = {"errors": [], "state": None, "dropped": 0}
        self._stop = threading.Event()
        if feed is not None:
            self.add_feed("0", feed)
        try:
            self.httpd = _QuietHTTPServer((host, port), self._handler())
        except OSError as exc:
            raise ConfigError(f"--view cannot listen on {host}:{port}: {exc.strerror} — "
                              "choose another port") from None
        self.httpd.daemon_threads = True
        self._threads = [threading.Thread(target=self._publish, name="skinhil-view-updates",
                                          daemon=True)]
        self._serving = threading.Thread(target=self.httpd.serve_forever, name="skinhil-view",
                                         daemon=True)

    @property
    def feed(self) -> ViewFeed | None:
        """The first board's feed (None before any board)."""
        with self._clients_lock:
            return next(iter(self.feeds.values()), None)

    def add_feed(self, key: str, feed: ViewFeed) -> None:
        """Show board ``key``'s feed too (pages list the boards and pick one)."""
        with self._clients_lock:
            self.feeds[str(key)] = feed

    @property
    def url(self) -> str:
        """The page's address."""
        host, port = self.httpd.server_address[:2]
        name = host.decode() if isinstance(host, bytes) else str(host)
        return f"http://{name}:{port}/"

    def start(self) -> ViewServer:
        for t in (*self._threads, self._serving):
            t.start()
        log.info("live view at %s", self.url)
        return self

    def close(self, reason: str = "the receiver stopped") -> None:
        """End the run on every page (a last update, then the ``end`` event with
        ``reason`` unless a feed already has one), then stop serving."""
        self._stop.set()
        for t in self._threads:
            t.join(timeout=2.0)
        with self._clients_lock:
            feeds = dict(self.feeds)
        for key, feed in feeds.items():
            feed.end_run(reason)
            self._broadcast(key, json.dumps(feed.update(), separators=(",", ":")))
            self._broadcast(key, END)
        end = time.monotonic() + END_FLUSH_S
        while time.monotonic() < end:
            with self._clients_lock:
                if all(q.empty() for _, q in self._clients):
                    break
            time.sleep(0.02)
        self.httpd.shutdown()
        self.httpd.server_close()
        self._serving.join(timeout=2.0)

    def _broadcast(self, key: str, text: str) -> None:
        with self._clients_lock:
            queues = [q for k, q in self._clients if k == key]
        for q in queues:
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

    def _publish(self) -> None:
        next_t = time.monotonic()
        while not self._stop.is_set():
            next_t += self.period_s
            self._stop.wait(max(0.0, next_t - time.monotonic()))
            if self._stop.is_set():
                return
            with self._clients_lock:
                feeds = dict(self.feeds)
                watched = {k for k, _ in self._clients}
            for key, feed in feeds.items():
                msg = feed.update()  # drained whether watched or not: nothing piles up
                msg["boards"] = list(feeds)  # boards that began to send since are listed
                if key in watched:
                    self._broadcast(key, json.dumps(msg, separators=(",", ":")))

    def _pick_feed(self, wanted: str | None, wait_s: float) -> tuple[str, ViewFeed] | None:
        """The feed of board ``wanted`` (the first board's when None or unknown), waiting up
        to ``wait_s`` for a first board to send."""
        end = time.monotonic() + wait_s
        while True:
            with self._clients_lock:
                if wanted in self.feeds:
                    return str(wanted), self.feeds[str(wanted)]
                if self.feeds:
                    key = next(iter(self.feeds))
                    return key, self.feeds[key]
            if self._stop.is_set() or time.monotonic() >= end:
                return None
            time.sleep(0.1)

    def _stream(self, handler: BaseHTTPRequestHandler, wanted: str | None) -> None:
        q: queue.Queue[str] = queue.Queue(maxsize=QUEUE_UPDATES)
        handler.send_response(HTTPStatus.OK)
        handler.send_header("Content-Type", "text/event-stream")
        handler.send_header("Cache-Control", "no-cache")
        handler.end_headers()
        try:
            picked = None
            while picked is None and not self._stop.is_set():
                picked = self._pick_feed(wanted, 1.0)
                if picked is None:  # no board has sent yet
                    handler.wfile.write(b": waiting for a board\n\n")
                    handler.wfile.flush()
            if picked is None:
                return
            key, feed = picked
            with self._clients_lock:
                self._clients.append((key, q))
                boards = list(self.feeds)
            try:
                hello = {**feed.hello(), "board": key, "boards": boards}
                config = json.dumps(hello, separators=(",", ":"))
                handler.wfile.write(f"event: config\ndata: {config}\n\n".encode())
                handler.wfile.flush()
                while True:
                    try:
                        text = q.get(timeout=1.0)
                    except queue.Empty:
                        if self._stop.is_set():
                            break
                        handler.wfile.write(b": alive\n\n")
                    else:
                        if text == END:
                            run = json.dumps(feed.run_state())
                            handler.wfile.write(f"event: end\ndata: {run}\n\n".encode())
                            handler.wfile.flush()
                            break
                        handler.wfile.write(f"event: update\ndata: {text}\n\n".encode())
                    handler.wfile.flush()
            finally:
                with self._clients_lock:
                    self._clients.remove((key, q))
        except (BrokenPipeError, ConnectionResetError):
            pass

    def _pick_psp(self, body: bytes) -> None:
        """A page picked PSP sensors: ``{"board": KEY, "sensors": [...]}``."""
        try:
            req = json.loads(body or b"{}")
            key, sensors = str(req.get("board", "0")), [int(a) for a in req["sensors"]]
        except (json.JSONDecodeError, KeyError, TypeError, ValueError, AttributeError):
            return
        with self._clients_lock:
            feed = self.feeds.get(key)
        if feed is not None:
            feed.pick_psp_sensors(sensors)

    def _report(self, body: bytes) -> None:
        """A page's report: malformed ones ignored; its errors kept (the first
        :data:`KEPT_ERRORS`, the rest counted in ``errors_dropped``) and logged as WARNING
        lines (the first :data:`LOGGED_ERRORS`, then counted only), so a page that floods
        cannot flood the terminal or the memory."""
        try:
            report = json.loads(body or b"{}")
        except (ValueError, UnicodeDecodeError, RecursionError):
            return
        if not isinstance(report, dict):
            return
        if report.get("kind") == "error":
            message = str(report.get("message", ""))[:2000]
            reports = self.client_reports
            reports["error_count"] = reports.get("error_count", 0) + 1
            if len(reports["errors"]) < KEPT_ERRORS:
                reports["errors"].append(message)
            else:
                reports["errors_dropped"] = reports.get("errors_dropped", 0) + 1
            n = reports["error_count"]
            if n <= LOGGED_ERRORS:
                log.warning("the live view page reported an error: %s%s", message,
                            " (further errors are counted, not logged: GET /client)"
                            if n == LOGGED_ERRORS else "")
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
                    query = parse_qs(urlsplit(self.path).query)
                    server._stream(self, query.get("board", [None])[0])
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
                text = self.headers.get("Content-Length") or "0"
                if not (text.isascii() and text.isdigit() and int(text) <= MAX_REPORT_BYTES):
                    self.close_connection = True  # a body of unknown length: not read
                    self._send(b"bad Content-Length", "text/plain", HTTPStatus.BAD_REQUEST)
                    return
                body = self.rfile.read(int(text))
                if self.path.split("?", 1)[0] == "/client":
                    server._report(body)
                elif self.path.split("?", 1)[0] == "/psp":
                    server._pick_psp(body)
                self._send(b"", "text/plain", HTTPStatus.NO_CONTENT)

        return Handler
