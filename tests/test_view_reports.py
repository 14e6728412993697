"""The live view's report endpoint (``POST /client``) takes anything a page or a stranger
sends without a traceback on the command's terminal, and a page that floods it with error
reports cannot flood the terminal or the memory: a few WARNING lines, a bounded list, the
rest counted."""

from __future__ import annotations

import json
import logging
import socket
import urllib.request

from skinhil.view.server import KEPT_ERRORS, LOGGED_ERRORS, ViewServer


def _raw(port: int, request: bytes) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(request)
        s.shutdown(socket.SHUT_WR)
        chunks = []
        while chunk := s.recv(65536):
            chunks.append(chunk)
    return b"".join(chunks)


def _post(port: int, body: bytes, length: str | None = None) -> bytes:
    head = (f"POST /client HTTP/1.1\r\nHost: x\r\nContent-Length: "
            f"{len(body) if length is None else length}\r\nConnection: close\r\n\r\n")
    return _raw(port, head.encode() + body)


def test_malformed_reports_and_an_error_flood(capfd, caplog) -> None:
    server = ViewServer(None, period_s=1.0).start()  # no board: the server alone
    port = int(server.url.rsplit(":", 1)[1].strip("/"))
    caplog.set_level(logging.DEBUG, logger="skinhil.view.server")
    try:
        for length in ("abc", "-5", "1e9", str(10**30), "١٢"):  # not a plain byte count
            assert b" 400 " in _post(port, b"{}", length).split(b"\r\n")[0]
        for body in (b"[1, 2]", b"\xff\xfe", b"[" * 60_000, b"\"text\"", b"null",
                     b'{"kind": "error", "message": {"a": 1}}'):
            assert b" 204 " in _post(port, body).split(b"\r\n")[0]
        assert b"400" in _raw(port, b"GARBAGE\r\n\r\n")
        flood = KEPT_ERRORS + 20
        for k in range(flood):
            _post(port, json.dumps({"kind": "error", "message": f"boom {k}"}).encode())
        with urllib.request.urlopen(f"{server.url}client", timeout=5) as r:
            reports = json.loads(r.read())
    finally:
        server.close()
    warnings = [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert len(warnings) == LOGGED_ERRORS
    assert len(reports["errors"]) == KEPT_ERRORS
    assert reports["error_count"] == flood + 1
    assert reports["errors_dropped"] == flood + 1 - KEPT_ERRORS
    assert "Traceback" not in capfd.readouterr().err
