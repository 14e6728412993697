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
from harness.refusals import refusal_failures
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
    "overlapping presses above 100 N": (
        '[[stimulus]]\nname = "p"\nforces = { 15 = [0, 0, -100] }\n'
        + '[[event]]\nstart_s = 0\nstimulus = "p"\n' * 3, "at most 100 N"),
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
    cases += _cases_of_issue_32(tmp, loop)
    for name, (_, word) in HOSTILE.items():
        cases.append(Case(f"listen --model {name}",
                          ("listen", *loop, "--model", str(tmp / f"{_slug(name)}.npz")), word))
    if os.geteuid() != 0 or shutil.which("setpriv") is not None:
        cases.append(Case("listen --model unreadable",
                          ("listen", *loop, "--model", str(tmp / "unreadable.npz")),
                          "permission denied", tuple(_DROP_DAC if os.geteuid() == 0 else ())))
    return cases


AS_A_USER = ("schedule: not UTF-8", "schedule on serve", "simulate --duration 1e5",
             "--seed 2^64", "--cpu 4096", "--bitrate 0 (CAN)", "listen --duration 0",
             "demo --duration 1e9", "--workers 0", "simulate --out /dev/full",
             "train --out missing folder", "unknown command", "missing value", "no command",
             "demo --model of another size", "listen --model pickle",
             "serve --score over its --schedule", "listen --record over its --model",
             "replay of a capture with a flipped bit", "--udp-allow '127.0.0.1:0'")
"""Cases that also run as a program, as a user runs them (one or more per command and kind
of refusal; those with an environment prefix always do); every case without a prefix runs
in-process in :func:`test_bad_inputs_refused_in_process` (a program's start-up is most of a
case's time: 80 programs took 100-220 s of the CI's budget)."""


def _cases_of_issue_32(tmp: Path, loop: tuple[str, ...]) -> list[Case]:
    """Replay, scoring, decoder and lab options, and paths that collide."""
    good, sched = str(tmp / "good338.npz"), str(tmp / "start_s_true.toml")
    valid_sched = str(tmp / "valid.toml")
    cap = str(tmp / "good.skcap")
    replay = ("serve", *loop, "--replay", cap)
    listen = ("listen", *loop, "--model", good)
    udp_listen = ("listen", "--udp", "0", "--model", good)
    cases = [
        Case("--response-window 1e308", ("serve", *loop, "--response-window", "1e308"),
             "--response-window"),
        Case("replay --response-window 1e308", (*replay, "--response-window", "1e308"),
             "--response-window"),
        Case("listen --model with escapes in its labels",
             ("listen", *loop, "--model", str(tmp / "escapes.npz")), "stimulus ids"),
        Case("demo with an unwritable cache", ("demo", "--duration", "2"), "XDG_CACHE_HOME",
             ("env", "XDG_CACHE_HOME=/proc/nope")),
        Case("compile with an unwritable cache", ("compile",), "NUMBA_CACHE_DIR",
             ("env", "NUMBA_CACHE_DIR=/proc/nope")),
        Case("serve --score over its --schedule", ("serve", *loop, "--schedule", valid_sched,
                                                   "--score", valid_sched), "overwrite"),
        Case("listen --record over its --model", (*listen, "--record", good), "overwrite"),
        Case("serve --record and --score one file",
             ("serve", *loop, "--record", str(tmp / "x.skcap"), "--score",
              str(tmp / "x.skcap")), "is also"),
        Case("simulate --out over its --schedule",
             ("simulate", "--schedule", sched, "--out", sched), "overwrite"),
        Case("replay --score over the recording", (*replay, "--score", cap), "overwrite"),
        Case("serve --truth and --score one file",
             ("serve", *loop, "--score", str(tmp / "s.json"), "--truth", str(tmp / "s.json")),
             "is also"),
        Case("replay --truth", (*replay, "--truth", str(tmp / "t.jsonl")), "drop --truth"),
        Case("replay --grasp-truth", (*replay, "--grasp-truth", str(tmp / "g.bin")),
             "drop --grasp-truth"),
        Case("replay --markers", (*replay, "--markers"), "drop --markers"),
        Case("serve --markers without --score", ("serve", *loop, "--markers"),
             "add --score FILE or drop --markers"),
        Case("listen --answer-with oracle without its truth",
             (*listen, "--answer", "--answer-with", "oracle"), "truth file"),
        Case("listen --answer-with without --answer", (*listen, "--answer-with", "random"),
             "add --answer"),
        Case("replay of a capture with a flipped bit",
             ("serve", *loop, "--replay", str(tmp / "flipped.skcap")), "CRC-32"),
        Case("simulate --size 3x3 --stimulus B (fixed edge)",
             ("simulate", "--size", "3x3", "--stimulus", "B"), "fixed mass"),
        Case("serve --bitrate on a serial port", ("serve", *loop, "--bitrate", "1000"),
             "--baud"),
        Case("--baud 20", ("serve", *loop, "--baud", "20"), "--baud"),
        Case("--snr-db -1000", ("serve", *loop, "--snr-db", "-1000"), "--snr-db"),
        Case("--snr-db 1e308", ("simulate", "--snr-db", "1e308"), "--snr-db"),
        Case("demo --duration 1e-9", ("demo", "--duration", "1e-9"), "--duration"),
        Case("--lsl of 100,000 characters", (*listen, "--lsl", "x" * 100_000), "--lsl"),
        Case("--lsl with a newline", (*listen, "--lsl", "a\nb"), "--lsl"),
        Case("--udp-allow on a serial listen", (*listen, "--udp-allow", "127.0.0.1"),
             "--udp"),
        Case("--udp-max-sources on a serial listen", (*listen, "--udp-max-sources", "3"),
             "--udp"),
        Case("replay --speed 1e-300 (1e300 s)", (*replay, "--speed", "1e-300"), "--speed"),
        Case("replay of classic CAN frames onto CAN FD",
             ("serve", "--can", "vcan0", "--fd", "--replay", str(tmp / "classic.asc")),
             "--fd"),
    ]
    for value in ("", ",", "localhost", "999.1.1.1", "127.0.0.1:abc", "127.0.0.1:0"):
        cases.append(Case(f"--udp-allow {value!r}", (*udp_listen, "--udp-allow", value),
                          "--udp-allow"))
    for option in (("--stopped",), ("--size", "4x4"), ("--snr-db", "20"),
                   ("--board-id", "3"), ("--duration", "0.01"), ("--seed", "9")):
        cases.append(Case(f"replay {' '.join(option)}", (*replay, *option), option[0]))
    return cases


def _issue_32_files(tmp: Path) -> None:
    """The files the cases of :func:`_cases_of_issue_32` read."""
    import can
    import numpy as np
    from harness.hostile_models import _entries, _signed, _write

    import protocols
    from protocols.capture import CaptureHeader, CaptureWriter

    good = write_good(tmp / "good338.npz", n_channels=338)
    header, arrays = _entries(good)
    arrays["classes"] = np.array(["\x1b[31mred", "\x1b]0;title\x07", "c"])
    header["classes_kind"] = "str"
    _write(tmp / "escapes.npz", _signed(header, arrays), arrays)
    (tmp / "valid.toml").write_text('[[event]]\nstart_s = 0\nstimulus = "A"\n')
    enc = protocols.SerialEncoder()
    units = [enc.events(protocols.events.make_events(np.array([k * 1000]), np.array([k])),
                        (k + 1) * 1000) for k in range(20)]
    with open(tmp / "good.skcap", "wb") as f:
        w = CaptureWriter(f, CaptureHeader(3, "serial", 100, 0))
        for k, u in enumerate(units):
            w.write(k * 1_000_000, k * 1000, u)
        w.close()
    raw = bytearray((tmp / "good.skcap").read_bytes())
    raw[len(raw) // 2] ^= 0x04
    (tmp / "flipped.skcap").write_bytes(bytes(raw))
    frames = protocols.CanEncoder().events(
        protocols.events.make_events(np.arange(10) * 100, np.arange(10)), 1000)
    with can.Logger(str(tmp / "classic.asc")) as log:
        for k, fr in enumerate(frames):
            log.on_message_received(can.Message(timestamp=1.0 + k * 1e-3,
                                                arbitration_id=fr.arbitration_id,
                                                data=fr.data, is_extended_id=False))


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("bad")
    good = write_good(tmp / "good.npz")
    for name, (make, _) in HOSTILE.items():
        make(tmp / f"{_slug(name)}.npz", good)
    pickled(tmp / "pickle.npz", good)
    _issue_32_files(tmp)
    unreadable = tmp / "unreadable.npz"
    shutil.copy(good, unreadable)
    unreadable.chmod(0)
    return tmp


def test_bad_inputs_refused_with_one_line(files: Path, warm_kernels: None) -> None:
    every = _bad_cases(files)
    cases = [c for c in every if c.prefix or c.name in AS_A_USER]
    assert len(cases) == len(AS_A_USER) + sum(1 for c in every if c.prefix)

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


def test_bad_inputs_refused_in_process(files: Path, capsys) -> None:
    """Every case that needs no environment of its own, run through ``skinhil.cli.main`` in
    this process: one ``skinhil: error:`` line, status 2."""
    cases = [c for c in _bad_cases(files) if not c.prefix]
    assert len(cases) >= 110
    failures = refusal_failures(cases, capsys)
    assert not failures, "\n".join(failures)


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
