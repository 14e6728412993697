"""The machine-readable ends of ``serve`` and ``listen`` (docs/process-output.md): the ready
line (on stdout with ``--json``, to ``--ready-fd N`` in any mode) comes once the link is
open and before the run's output, the summary line last; every field either carries is
documented on the reference page; ``serve --help`` reads in sections."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from harness.host_link import host_beside_serve
from harness.hostile_models import write_good
from harness.serve import REPO, RUN_DIR, ServeProcess, serve_env

from skinhil.cli.parser import build_parser
from skinhil.process_output import FORMAT, READY, SUMMARY, last_record, records

DOC = REPO / "docs" / "process-output.md"


def _undocumented(record: dict[str, Any]) -> list[str]:
    """The keys of ``record`` (and of its ``versions``) the reference page does not name."""
    text = DOC.read_text(encoding="utf-8")
    keys = [k for k in record if k != "versions"] + [f"versions.{k}" for k in
                                                     record.get("versions", {})]
    return [k for k in keys if f"`{k}`" not in text]


def _read_fd_line(fd: int, timeout_s: float) -> bytes:
    """What the pipe ``fd`` carries up to its end of file (within ``timeout_s``)."""
    end = time.monotonic() + timeout_s
    data = b""
    os.set_blocking(fd, False)
    try:
        while time.monotonic() < end:
            try:
                chunk = os.read(fd, 4096)
            except BlockingIOError:
                time.sleep(0.02)
                continue
            if not chunk:
                return data
            data += chunk
    finally:
        os.close(fd)
    raise AssertionError(f"no end of file on the ready fd within {timeout_s:g} s: {data!r}")


def test_serve_json_opens_with_the_ready_line_and_ends_with_the_summary() -> None:
    serve = ServeProcess("--port", "loop://", "--duration", "0.5", "--json")
    assert serve.wait(120) == 0, serve.stderr
    first, last = serve.lines[0], serve.lines[-1]
    assert first["type"] == READY and last["type"] == SUMMARY, serve.lines
    assert first["format"] == FORMAT and first["command"] == "serve"
    assert first["pid"] == serve.proc.pid and first["link_up"] is True
    assert first["versions"]["wire"] == [3] and first["channels"] == 338
    assert (first["size"], first["duration_s"], first["board_id"]) == ("6x6", 0.5, 0)
    assert [x["type"] for x in serve.lines].count(READY) == 1
    assert last["board_time_s"] == 0.5 and last["ticks"] == 500
    assert not _undocumented(first) and not _undocumented(last), (
        _undocumented(first), _undocumented(last))


def test_ready_fd_carries_the_ready_line_while_serve_runs_quiet() -> None:
    read_end, write_end = os.pipe()
    proc = subprocess.Popen(
        [sys.executable, "-m", "skinhil", "serve", "--port", "loop://", "--duration", "2",
         "--quiet", "--ready-fd", str(write_end)], cwd=RUN_DIR, env=serve_env(),
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        pass_fds=(write_end,))
    os.close(write_end)
    try:
        data = _read_fd_line(read_end, 120)
        running = proc.poll() is None  # the line came, and the fd closed, before the end
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert running, "the ready line came only as serve ended"
    assert data.endswith(b"\n") and data.count(b"\n") == 1, data
    ready = json.loads(data)
    assert ready["type"] == READY and ready["pid"] == proc.pid, ready
    assert out == "" and "ready" not in err  # --quiet: nothing else but errors


def test_listen_json_opens_with_the_ready_line_and_ends_with_the_summary(
        tmp_path: Path) -> None:
    model = write_good(tmp_path / "m.npz", n_channels=338)
    listen = ServeProcess("--port", "loop://", "--model", str(model), "--duration", "0.5",
                          "--json", command="listen")
    ready = listen.wait_ready()
    assert listen.wait(60) == 0, listen.stderr
    assert listen.lines[0] == ready and listen.lines[-1]["type"] == SUMMARY, listen.lines
    assert ready["command"] == "listen" and ready["pid"] == listen.proc.pid
    assert ready["boards"] == [0] and ready["answer"] is None
    assert ready["model"] == str(model) and ready["versions"]["wire"] == [3, 4]
    summary = listen.summary()
    assert summary["link"]["events_decoded"] == 0 and summary["accuracy"] is None
    assert "Ctrl-C stops" not in listen.stderr  # with --json the banner is not printed
    assert not _undocumented(ready) and not _undocumented(summary), (
        _undocumented(ready), _undocumented(summary))


def test_listen_json_summary_names_the_suite_case_the_board_announced(tmp_path: Path) -> None:
    """Over a real pty: ``serve --suite`` announces its case in the SESSION (SPEC §3.7) and
    ``listen --json``'s summary carries what it heard under ``session``."""
    model = write_good(tmp_path / "m.npz", n_channels=338)
    board, host = host_beside_serve(
        tmp_path, [sys.executable, "-m", "skinhil", "listen", "--port", "{HOST}", "--model",
                   str(model), "--json"],
        ["--suite", "tactile-v1:vibration", "--seed", "1000003", "--duration", "0.5",
         "--quiet"], timeout_s=240, own_end_s=30, host_ready=True)
    assert board.returncode == 0, board.stderr
    summary = last_record(records(host.stdout), SUMMARY)
    assert summary is not None, (host.stdout[-2000:], host.stderr[-2000:])
    session = summary["session"]
    assert session["suite"] == {"id": "tactile-v1", "name": "tactile", "version": 1,
                                "case": "vibration"}, session
    assert session["held_object"] is False
    assert list(session["tasks"]) == ["vibration"]
    assert session["tasks"]["vibration"]["classes"] == [50, 100, 200, 300]


def test_a_ready_fd_that_is_not_open_is_one_line() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "skinhil", "serve", "--port", "loop://", "--duration", "1",
         "--ready-fd", "1000"], cwd=RUN_DIR, env=serve_env(), stdin=subprocess.DEVNULL,
        capture_output=True, text=True, timeout=60)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("skinhil: error: --ready-fd 1000: no such open file "
                               "descriptor"), lines


def test_serve_help_is_in_sections_with_every_option_in_one() -> None:
    parser = build_parser("serve")
    serve = next(a for a in parser._actions if a.dest == "command").choices["serve"]
    titles = [g.title for g in serve._action_groups]
    for section in ("link", "stimulus and world", "board", "model", "scoring", "real time",
                    "outputs"):
        assert any(t is not None and t.startswith(section) for t in titles), (section, titles)
    loose = [a.option_strings for g in serve._action_groups if g.title == "options"
             for a in g._group_actions if a.dest != "help"]
    assert loose == [], loose
    assert len(serve._actions) - 1 >= 40  # every option, none lost to the sections


def test_records_take_json_objects_by_type_and_skip_the_rest() -> None:
    text = "\n".join([
        "skinhil serve: compiling ... Ctrl-C stops",
        json.dumps({"type": READY, "pid": 1}),
        '{"type": "summary", "sent": 1',  # cut short
        "[1, 2]",
        json.dumps({"type": SUMMARY, "sent": 2}),
        json.dumps({"type": SUMMARY, "sent": 3}),
    ])
    items = records(text)
    assert [x["type"] for x in items] == [READY, SUMMARY, SUMMARY]
    assert last_record(items, SUMMARY) == {"type": SUMMARY, "sent": 3}
    assert last_record(items, "status") is None
