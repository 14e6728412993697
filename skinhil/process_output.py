"""The machine-readable ends of ``skinhil serve`` and ``skinhil listen`` (docs/process-output.md).

A process that runs a link says twice, as one JSON object on one line, what a program
driving it needs:

- the **ready line** (``"type": "ready"``), once its link is open and it is about to run:
  the command, the link, the versions, the process id. With ``--json`` it is a line of
  stdout among the others; with ``--ready-fd N`` it is written to the inherited file
  descriptor N, which is then closed (a reader sees the line, then end of file), whatever
  the output mode (text, ``--json``, ``--quiet``);
- the **summary line** (``"type": "summary"``), last, with ``--json``: the board's
  :class:`firmware_sim.board.BoardSummary`, the receiver's counters.

Other lines of ``--json`` (``status``, ``link``, ``decision``, ...) come between them. A
reader takes each line that is a JSON object (:func:`records`) and picks by ``type``
(:func:`last_record`), never by matching text.
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Iterable, Mapping
from typing import Any

from skinhil import __version__
from skinhil.errors import ConfigError

FORMAT = 1
"""Version of these lines' layout (the ``format`` field of the ready line): raised when a
stable field changes meaning or goes away; new fields do not raise it."""
READY = "ready"
"""``type`` of the ready line."""
SUMMARY = "summary"
"""``type`` of the summary line."""


def ready_record(command: str, link: str, link_up: bool, wire_versions: Iterable[int],
                 **fields: Any) -> dict[str, Any]:
    """The ready line of ``command`` (``"serve"``, ``"listen"``) running on ``link`` (the
    link as the command describes it); ``link_up``: the link is open as the run starts;
    ``wire_versions``: the protocol versions it sends or
    reads; ``fields``: the command's own (board id, model, ...)."""
    return {"type": READY, "format": FORMAT, "command": command, "pid": os.getpid(),
            "link": link, "link_up": bool(link_up),
            "versions": {"skinhil": __version__, "wire": sorted(int(v) for v in wire_versions),
                         "python": platform.python_version()},
            **fields}


def line(record: Mapping[str, Any]) -> str:
    """``record`` as one line of JSON (no newline inside, none at the end)."""
    return json.dumps(record)


def check_ready_fd(fd: int | None) -> int | None:
    """``fd`` if it is None or an open file descriptor, else a one-line :class:`ConfigError`
    (checked at start, before any work)."""
    if fd is None:
        return None
    try:
        os.fstat(fd)
    except OSError:
        raise ConfigError(f"--ready-fd {fd}: no such open file descriptor — open it in the "
                          f"program that starts this one and pass it (e.g. '{fd}>FILE' in a "
                          "shell, pass_fds in Python)") from None
    return fd


def write_ready_fd(fd: int, record: Mapping[str, Any]) -> None:
    """Write ``record`` as one line to ``fd`` and close it. A reader gone away (a closed
    pipe) is not this process's failure: the run goes on."""
    data = (line(record) + "\n").encode("utf-8")
    try:
        while data:
            data = data[os.write(fd, data):]
    except OSError:
        pass
    finally:
        try:
            os.close(fd)
        except OSError:
            pass


def records(text: str) -> list[dict[str, Any]]:
    """Every line of ``text`` that is a JSON object, in order (other lines are skipped)."""
    out = []
    for raw in text.splitlines():
        raw = raw.strip()
        if not raw.startswith("{"):
            continue
        try:
            item = json.loads(raw)
        except ValueError:
            continue
        if isinstance(item, dict):
            out.append(item)
    return out


def last_record(items: Iterable[Mapping[str, Any]], kind: str) -> dict[str, Any] | None:
    """The last of ``items`` whose ``type`` is ``kind``, or None."""
    found = None
    for item in items:
        if item.get("type") == kind:
            found = dict(item)
    return found
