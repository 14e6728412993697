"""``bench --resume`` reads its ``summary.json`` as untrusted input: whatever it holds, the
run is refused with one ``skinhil: error:`` line and exit status 2 (docs/campaigns.md), in
bounded time and memory, before any case is played.

Each row is one hostile or mistaken summary, run as a user runs it (``python -m skinhil bench
CAMPAIGN --resume --out DIR``): a FIFO nobody writes to, ``/dev/zero``, a folder, bytes that
are not UTF-8 or not JSON, JSON nested past the parser's depth, a number of 5,000 digits, and
summaries with the right format and the campaign's digest but a missing, renamed or mistyped
key, an unknown outcome, a case the campaign does not hold, or one case twice.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from harness.serve import REPO, RUN_DIR, serve_env

from skinhil.campaign.campaign_file import load_campaign
from skinhil.campaign.summary_file import load_summary, new_summary
from skinhil.errors import ConfigError
from skinhil.model.schedule_file import READ_TIMEOUT_S
from skinhil.schemas import validate

SMOKE = REPO / "examples" / "campaigns" / "smoke.toml"
PARALLEL = 3
"""Commands run at once (2 cores: most of their time is Python's start-up)."""


def _good() -> dict[str, Any]:
    """A summary of the smoke campaign with its first case played, as bench writes it."""
    campaign = load_campaign(SMOKE)
    summary = new_summary(campaign, "bench pty pair")
    case = campaign.cases()[0]
    summary["cases"].append({
        "id": case.id, "scenario": case.scenario.name, "parameters": case.parameters,
        "repetition": 1, "seed": case.seed, "outcome": "passed", "message": "",
        "criteria": [{"criterion": "decisions >= 1", "value": 3, "holds": True}],
        "errors": [], "rig": {"board": {"lateness_max_ms": 1.0, "deadline_misses": 0,
                                        "ticks": 1500, "fifo_drops": 0, "link_losses": 0},
                              "link": {"frames_ok": 900, "crc_errors": 0, "malformed": 0,
                                       "frames_lost": 0}},
        "started": "2000-01-01T00:00:00+00:00", "wall_s": 4.2, "folder": "cases/0001"})
    return summary


def _edit(change: Callable[[dict[str, Any]], object]) -> Callable[[Path], None]:
    """A row that writes the good summary changed by ``change``."""
    def write(path: Path) -> None:
        summary = copy.deepcopy(_good())
        change(summary)
        path.write_text(json.dumps(summary), encoding="utf-8")
    return write


def _text(text: str | bytes) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_bytes(text.encode() if isinstance(text, str) else text)
    return write


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _zero(path: Path) -> None:
    path.symlink_to("/dev/zero")


def _folder(path: Path) -> None:
    path.mkdir()


def _second_twice(s: dict[str, Any]) -> None:
    s["cases"].append(dict(s["cases"][0]))


ROWS: dict[str, tuple[Callable[[Path], None], str]] = {
    # name: (how summary.json is made, a word of the refusal)
    "FIFO nobody writes to": (_fifo, "summary"),
    "/dev/zero": (_zero, "larger than"),
    "a folder": (_folder, "cannot be read"),
    "not UTF-8": (_text(b"\xff\xfe{}"), "UTF-8"),
    "not JSON": (_text("{format: 1"), "not JSON"),
    "empty": (_text(""), "not JSON"),
    "a list": (_text("[1, 2]"), "not a skinhil campaign summary"),
    "nested 100,000 deep": (_text("[" * 100_000 + "]" * 100_000), "nest"),
    "5,000-digit number": (_text('{"version": ' + "9" * 5000 + "}"), "not JSON"),
    "cases missing": (_edit(lambda s: s.pop("cases")), "$ lacks a key"),
    "totals renamed": (_edit(lambda s: s.__setitem__("total", s.pop("totals"))), "'total'"),
    "campaign a list": (_edit(lambda s: s.__setitem__("campaign", [])), "$.campaign"),
    "cases a string": (_edit(lambda s: s.__setitem__("cases", "all")), "$.cases"),
    "a case a number": (_edit(lambda s: s["cases"].__setitem__(0, 7)), "$.cases[0]"),
    "a case without id": (_edit(lambda s: s["cases"][0].pop("id")), "$.cases[0]"),
    "an id not a string": (_edit(lambda s: s["cases"][0].__setitem__("id", [1])),
                           "$.cases[0].id"),
    "unknown outcome": (_edit(lambda s: s["cases"][0].__setitem__("outcome", "skipped")),
                        "$.cases[0].outcome"),
    "outcome null": (_edit(lambda s: s["cases"][0].__setitem__("outcome", None)),
                     "$.cases[0].outcome"),
    "digest missing": (_edit(lambda s: s["campaign"].pop("sha256")), "$.campaign"),
    "another campaign": (_edit(lambda s: s["campaign"].__setitem__("sha256", "0" * 64)),
                         "another campaign"),
    "a case not in the campaign": (_edit(lambda s: s["cases"][0].__setitem__("id", "x#1")),
                                   "does not hold"),
    "a case twice": (_edit(_second_twice), "a case twice"),
    "deep inside a case": (_edit(lambda s: s["cases"][0].__setitem__(
        "parameters", json.loads("[" * 500 + "]" * 500))), "$.cases[0].parameters"),
}


CLI_ROWS = ("FIFO nobody writes to", "/dev/zero", "nested 100,000 deep", "a case a number",
            "unknown outcome", "a case twice")
"""The rows also run as a user runs them (each costs a Python start-up)."""


def _bench(out: Path) -> tuple[subprocess.CompletedProcess[str], float]:
    """``bench --resume`` on ``out``; a model file that does not exist, so a summary taken
    by mistake ends in a refusal naming the model, never in a model trained for minutes."""
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "skinhil", "bench", str(SMOKE), "--resume",
                           "--out", str(out), "--model", str(out / "no-model.npz"),
                           "--quiet"], cwd=RUN_DIR, env=serve_env(), text=True,
                          capture_output=True, timeout=READ_TIMEOUT_S + 120,
                          stdin=subprocess.DEVNULL)
    return done, time.monotonic() - t0


def _made(tmp_path: Path, names: tuple[str, ...] | list[str]) -> dict[str, Path]:
    """Each row's --out folder with its summary.json made."""
    outs = {}
    for i, name in enumerate(names):
        out = tmp_path / f"run{i}"
        out.mkdir()
        ROWS[name][0](out / "summary.json")
        outs[name] = out
    return outs


def test_the_good_summary_is_valid_and_resumes(tmp_path: Path) -> None:
    """The rows' base summary is one the schema and the reader take: each row is refused
    for its change alone."""
    validate("campaign-summary", _good())
    (tmp_path / "summary.json").write_text(json.dumps(_good()), encoding="utf-8")
    campaign = load_campaign(SMOKE)
    assert load_summary(tmp_path / "summary.json", campaign)["cases"][0]["id"] == \
        campaign.cases()[0].id


@pytest.mark.parametrize("name", list(ROWS))
def test_every_hostile_summary_is_refused_in_one_line(name: str, tmp_path: Path) -> None:
    """The reader itself, row by row: a ConfigError of one line, in bounded time."""
    path = _made(tmp_path, [name])[name] / "summary.json"
    t0 = time.monotonic()
    with pytest.raises(ConfigError) as caught:
        load_summary(path, load_campaign(SMOKE))
    text = str(caught.value)
    assert "\n" not in text and len(text) < 600 and ROWS[name][1] in text, text
    assert time.monotonic() - t0 < READ_TIMEOUT_S + 5


def test_bench_refuses_hostile_summaries_with_status_2(tmp_path: Path) -> None:
    outs = _made(tmp_path, CLI_ROWS)
    with ThreadPoolExecutor(PARALLEL) as pool:
        results = dict(zip(CLI_ROWS, pool.map(lambda n: _bench(outs[n]), CLI_ROWS),
                           strict=True))
    bad = []
    for name, (done, wall_s) in results.items():
        err = done.stderr.strip().splitlines()
        if not (done.returncode == 2 and len(err) == 1 and err[0].startswith("skinhil: error:")
                and ROWS[name][1] in err[0] and not (outs[name] / "cases").exists()
                and wall_s < READ_TIMEOUT_S + 90):  # a loaded machine starts Python slowly
            bad.append((name, done.returncode, round(wall_s, 1), done.stderr[-600:]))
    assert not bad, bad
