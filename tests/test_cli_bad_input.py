"""Every bad input refused by the command line with one ``skinhil: error:`` line and exit
status 2, no traceback; every valid edge (sizes from 3x3 on serve, simulate, train and
listen) runs.

Each row is one input of a class: malformed schedules (wrong types, out of range, unknown
keys, too big, too deep), numbers out of range, outputs that cannot be written or would be
written elsewhere, hostile or mismatched decoder files, a port held by another program,
argparse's own errors. They run as a user runs them: ``python -m skinhil ...``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest
from harness.hostile_models import HOSTILE, pickled, write_good
from harness.serve import RUN_DIR, serve_env

PARALLEL = 3
"""Commands run at once (2 cores: most of their time is Python's start-up)."""
EDGE_SIZES = ("3x3", "4x4", "5x6", "3x8")

_DROP_DAC = ["setpriv", "--bounding-set", "-dac_override,-dac_read_search",
             "--inh-caps", "-dac_override,-dac_read_search"]


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]
    word: str
    """A word the error line says (case-insensitive)."""
    prefix: tuple[str, ...] = ()


def _run(argv: list[str], timeout_s: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "skinhil", *argv], cwd=RUN_DIR,
                          env=serve_env(), text=True, capture_output=True, timeout=timeout_s,
                          stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def warm_kernels() -> None:
    """Kernels compiled before the table (a cold cache adds a notice line)."""
    done = _run(["compile"], timeout_s=600)
    assert done.returncode == 0, done.stderr


SCHEDULES: dict[str, tuple[str, str]] = {
    # name: (TOML text, a word of the refusal)
    "onset_s string": ('[[stimulus]]\nname = "p"\nforces = { 15 = [0, 0, -0.1] }\n'
                       'onset_s = "abc"\n[[event]]\nstart_s = 0\nstimulus = "p"\n', "onset_s"),
    "force string": ('[[stimulus]]\nname = "p"\nforces = { 15 = "abc" }\n[[event]]\n'
                     'start_s = 0\nstimulus = "p"\n', "forces.15"),
    "force table": ('[[stimulus]]\nname = "p"\nforces = { 15 = { x = 1 } }\n[[event]]\n'
                    'start_s = 0\nstimulus = "p"\n', "forces.15"),
    "force booleans": ('[[stimulus]]\nname = "p"\nforces = { 15 = [true, false, true] }\n'
                       '[[event]]\nstart_s = 0\nstimulus = "p"\n', "forces.15"),
    "force 1e200 N": ('[[stimulus]]\nname = "p"\nforces = { 15 = [0, 0, -1e200] }\n'
                      '[[event]]\nstart_s = 0\nstimulus = "p"\n', "newtons"),
    "force two numbers": ('[[stimulus]]\nname = "p"\nforces = { 15 = [0, 1] }\n[[event]]\n'
                          'start_s = 0\nstimulus = "p"\n', "[fx, fy, fz]"),
    "mass not a number": ('[[stimulus]]\nname = "p"\nforces = { x = [0, 0, 1] }\n[[event]]\n'
                          'start_s = 0\nstimulus = "p"\n', "mass"),
    "stimulus id key": ('[[stimulus]]\nname = "p"\nid = 5\nforces = { 15 = [0, 0, -0.1] }\n'
                        '[[event]]\nstart_s = 0\nstimulus = "p"\n', "unknown key"),
    "event extra key": ('[[event]]\nstart_s = 0\nstimulus = "A"\nforce = 1\n', "unknown key"),
    "stimulus = [1]": ('[[event]]\nstart_s = 0\nstimulus = [1]\n', "unknown stimulus"),
    "start_s 1e308": ('[[event]]\nstart_s = 1e308\nstimulus = "A"\n', "start_s"),
    "start_s string": ('[[event]]\nstart_s = "0.5"\nstimulus = "A"\n', "start_s"),
    "start_s true": ('[[event]]\nstart_s = true\nstimulus = "A"\n', "start_s"),
    "start_s inf": ('[[event]]\nstart_s = inf\nstimulus = "A"\n', "start_s"),
    "start_s negative": ('[[event]]\nstart_s = -1\nstimulus = "A"\n', "start_s"),
    "decay 0": ('[[stimulus]]\nname = "p"\nforces = { 15 = [0, 0, -0.1] }\ndecay_tau_s = 0\n'
                '[[event]]\nstart_s = 0\nstimulus = "p"\n', "decay_tau_s"),
    "event not a table": ('event = [1, 2]\n', "not a table"),
    "stimulus not a list": ('stimulus = 3\n[[event]]\nstart_s = 0\nstimulus = "A"\n',
                            "list of tables"),
    "deep nesting": ("x = " + "[" * 100_000 + "]" * 100_000 + "\n", "deeply"),
    "no events": ('[[stimulus]]\nname = "p"\nforces = { 15 = [0, 0, -0.1] }\n', "no [[event]]"),
    "not TOML": ("[[event]\nstart_s = 1\n", "not valid TOML"),
    "over 4 MiB": ("#" * (5 * 2**20) + "\n[[event]]\nstart_s = 0\nstimulus = \"A\"\n",
                   "larger than"),
    "unknown section": ("[other]\na = 1\n", "unknown section"),
}


def _bad_cases(tmp: Path) -> list[Case]:
    cases = []
    for name, (text, word) in SCHEDULES.items():
        path = tmp / f"{name.replace(' ', '_')}.toml"
        path.write_text(text)
        cases.append(Case(f"schedule: {name}", ("simulate", "--schedule", str(path),
                                                "--out", str(tmp / "s.npz")), word))
    binary = tmp / "latin1.toml"
    binary.write_bytes(b"# \xff\xfe\n[[event]]\nstart_s = 0\nstimulus = 'A'\n")
    cases.append(Case("schedule: not UTF-8", ("simulate", "--schedule", str(binary)), "UTF-8"))
    cases.append(Case("schedule on serve", ("serve", "--port", "loop://", "--schedule",
                                            str(tmp / "start_s_true.toml")), "start_s"))
    loop = ("--port", "loop://")
    cases += [
        Case("simulate --duration 1e5", ("simulate", "--duration", "1e5"), "memory"),
        Case("simulate --duration -1", ("simulate", "--duration", "-1"), "--duration"),
        Case("simulate --duration nan", ("simulate", "--duration", "nan"), "--duration"),
        Case("--dt 1", ("simulate", "--dt", "1"), "--dt"),
        Case("--dt 1e-9", ("serve", *loop, "--dt", "1e-9"), "--dt"),
        Case("--dt inf", ("simulate", "--dt", "inf"), "--dt"),
        Case("--dt 1.5e-6 (not whole us)", ("serve", *loop, "--dt", "1.5e-6"),
             "whole number of microseconds"),
        Case("--seed -1", ("simulate", "--seed", "-1"), "--seed"),
        Case("--seed 2^64", ("train", "--out", str(tmp / "m.npz"), "--seed", str(2**64)),
             "--seed"),
        Case("--fifo 1e12", ("serve", *loop, "--fifo", "1e12"), "--fifo"),
        Case("--fifo 10^12", ("serve", *loop, "--fifo", str(10**12)), "--fifo"),
        Case("--status-period 1e308", ("serve", *loop, "--status-period", "1e308"),
             "--status-period"),
        Case("--tick 0", ("serve", *loop, "--tick", "0"), "--tick"),
        Case("--rest nan", ("serve", *loop, "--rest", "nan"), "--rest"),
        Case("--threads 0", ("serve", *loop, "--threads", "0"), "--threads"),
        Case("--cpu 4096", ("serve", *loop, "--cpu", "4096"), "--cpu"),
        Case("--cpu one", ("serve", *loop, "--cpu", "one"), "--cpu"),
        Case("--cpu with more threads", ("serve", *loop, "--cpu", "0", "--threads", "2"),
             "--cpu"),
        Case("--board-id 16", ("serve", *loop, "--board-id", "16"), "--board-id"),
        Case("--bitrate 0 (CAN)", ("serve", "--can", "vcan0", "--bitrate", "0"), "--bitrate"),
        Case("--bitrate 0 (UDP)", ("serve", "--udp", "127.0.0.1:9", "--bitrate", "0"),
             "--bitrate"),
        Case("--baud 0", ("serve", *loop, "--baud", "0"), "--baud"),
        Case("serve --duration 1e308", ("serve", *loop, "--duration", "1e308"), "--duration"),
        Case("listen --duration 0", ("listen", *loop, "--model", "m.npz", "--duration", "0"),
             "--duration"),
        Case("demo --duration 1e9", ("demo", "--duration", "1e9"), "--duration"),
        Case("--size 2x2", ("simulate", "--size", "2x2"), "--size"),
        Case("--size 300x300", ("simulate", "--size", "300x300"), "sensors"),
        Case("--size abc", ("serve", *loop, "--size", "abc"), "--size"),
        Case("--reps 0", ("train", "--out", str(tmp / "m.npz"), "--reps", "0"), "--reps"),
        Case("--workers 0", ("reproduce", "--out", str(tmp / "r"), "--workers", "0"),
             "--workers"),
        Case("--udp-max-sources 0", ("listen", "--udp", "0", "--model", "m.npz",
                                     "--udp-max-sources", "0"), "--udp-max-sources"),
        Case("--snr-db nan", ("simulate", "--snr-db", "nan"), "--snr-db"),
        # outputs
        Case("simulate --out run.txt", ("simulate", "--out", str(tmp / "run.txt")), ".npz"),
        Case("simulate --out /dev/full", ("simulate", "--out", "/dev/full"), "/dev/full"),
        Case("simulate --out missing folder", ("simulate", "--out",
                                               str(tmp / "nope" / "run.npz")), "does not exist"),
        Case("simulate --out a folder", ("simulate", "--out", str(tmp)), "folder"),
        Case("train --out missing folder", ("train", "--out", str(tmp / "nope" / "m.npz")),
             "does not exist"),
        Case("train --out run.txt", ("train", "--out", str(tmp / "m.txt")), ".npz"),
        Case("listen --record missing folder",
             ("listen", *loop, "--model", str(tmp / "good.npz"), "--size", "6x6", "--record",
              str(tmp / "nope" / "s.npz")), "does not exist"),
        # argparse's own
        Case("unknown command", ("bogus",), "invalid choice"),
        Case("unknown option", ("simulate", "--bogus"), "unrecognized arguments"),
        Case("missing value", ("serve", "--port"), "expected one argument"),
        Case("no link", ("serve",), "one of the arguments"),
        Case("bad choice", ("simulate", "--mechanics", "rubber"), "invalid choice"),
        Case("no command", (), "required"),
        # decoder files
        Case("demo --model of another size", ("demo", "--model", str(tmp / "good.npz"),
                                              "--duration", "1"), "channels"),
        Case("listen --model of another size", ("listen", *loop, "--model",
                                                str(tmp / "good.npz")), "channels"),
        Case("listen --model missing", ("listen", *loop, "--model", str(tmp / "none.npz")),
             "not found"),
        Case("listen --model pickle", ("listen", *loop, "--model", str(tmp / "pickle.npz")),
             "pickle"),
    ]
    for name, (_, word) in HOSTILE.items():
        cases.append(Case(f"listen --model {name}",
                          ("listen", *loop, "--model", str(tmp / f"{_slug(name)}.npz")), word))
    if os.geteuid() != 0 or shutil.which("setpriv") is not None:
        cases.append(Case("listen --model unreadable",
                          ("listen", *loop, "--model", str(tmp / "unreadable.npz")),
                          "permission denied", tuple(_DROP_DAC if os.geteuid() == 0 else ())))
    return cases


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("bad")
    good = write_good(tmp / "good.npz")
    for name, (make, _) in HOSTILE.items():
        make(tmp / f"{_slug(name)}.npz", good)
    pickled(tmp / "pickle.npz", good)
    unreadable = tmp / "unreadable.npz"
    shutil.copy(good, unreadable)
    unreadable.chmod(0)
    return tmp


def test_bad_inputs_refused_with_one_line(files: Path, warm_kernels: None) -> None:
    cases = _bad_cases(files)

    def one(case: Case) -> tuple[Case, subprocess.CompletedProcess[str]]:
        argv = [*case.prefix, sys.executable, "-m", "skinhil", *case.argv]
        try:
            return case, subprocess.run(argv, cwd=RUN_DIR, env=serve_env(), text=True,
                                        capture_output=True, timeout=60,
                                        stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired as exc:
            return case, subprocess.CompletedProcess(argv, -1, "", f"timed out: {exc}")

    with ThreadPoolExecutor(PARALLEL) as pool:
        results = list(pool.map(one, cases))
    failures = []
    for case, done in results:
        lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
        ok = (done.returncode == 2 and "Traceback" not in done.stderr and len(lines) == 1
              and lines[0].startswith("skinhil: error: ")
              and case.word.lower() in lines[0].lower())
        if not ok:
            failures.append(f"{case.name}: status {done.returncode}, stderr {done.stderr!r}")
    assert not failures, "\n".join(failures)
    assert len(results) >= 75


def test_port_held_by_uucp_lock_file_refused(warm_kernels: None, pty_pair) -> None:
    """A port another program holds by a UUCP lock file (``/var/lock/LCK..pts_N`` with its
    live pid) is busy; once that program is gone the stale lock is ignored, and the pty the
    test itself holds open on the other end is served."""
    lock_dir = Path("/var/lock")
    if not os.access(lock_dir, os.W_OK):
        pytest.skip("/var/lock is not writable here")
    lock = lock_dir / f"LCK..{pty_pair.path[len('/dev/'):].replace('/', '_')}"
    holder = subprocess.Popen(["sleep", "60"])
    try:
        lock.write_text(f"{holder.pid:10d}\n")
        done = _run(["serve", "--port", pty_pair.path, "--duration", "0.2", "--quiet"])
        lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
        assert done.returncode == 2 and len(lines) == 1, done.stderr
        assert "busy" in lines[0] and str(holder.pid) in lines[0], lines
        holder.kill()
        holder.wait()
        done = _run(["serve", "--port", pty_pair.path, "--duration", "0.2", "--quiet"])
        assert done.returncode == 0, done.stderr
    finally:
        holder.kill()
        holder.wait()
        lock.unlink(missing_ok=True)


def test_valid_edges_run(tmp_path: Path, warm_kernels: None) -> None:
    """Every size from 3x3 on serves, simulates, trains a decoder and listens with it."""
    runs = []
    for size in EDGE_SIZES:
        model = tmp_path / f"m{size}.npz"
        runs += [
            ["serve", "--port", "loop://", "--size", size, "--duration", "0.2", "--quiet"],
            ["simulate", "--size", size, "--duration", "0.05", "--no-progress",
             "--out", str(tmp_path / f"s{size}.npz")],
            ["train", "--size", size, "--reps", "6", "--no-progress", "--out", str(model)],
        ]
    # --dt's upper edge, 10 ms, under the linear mechanics (the geometric one refuses steps
    # above its RK4 stability bound itself, with a line of its own)
    runs += [["simulate", "--mechanics", "linear", "--dt", "1e-2", "--duration", "0.05",
              "--no-progress", "--out", str(tmp_path / "dt.npz")],
             ["simulate", "--dt", "1e-6", "--duration", "0.002", "--no-progress",
              "--out", str(tmp_path / "dt6.npz")]]
    with ThreadPoolExecutor(PARALLEL) as pool:
        results = list(pool.map(_run, runs))
    listens = [["listen", "--port", "loop://", "--size", size, "--model",
                str(tmp_path / f"m{size}.npz"), "--duration", "0.3"] for size in EDGE_SIZES]
    with ThreadPoolExecutor(PARALLEL) as pool:
        results += list(pool.map(_run, listens))
    failed = [(argv, r.returncode, r.stderr[-400:]) for argv, r in zip(runs + listens, results,
                                                                         strict=True)
              if r.returncode != 0 or "Traceback" in r.stderr]
    assert not failed, failed
    for size in EDGE_SIZES:
        assert (tmp_path / f"s{size}.npz").stat().st_size > 0
        out = next(r.stdout for argv, r in zip(runs, results, strict=False)
                   if argv[0] == "simulate" and size in argv)
        assert f"wrote {tmp_path / f's{size}.npz'}" in out
