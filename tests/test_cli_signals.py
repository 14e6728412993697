"""Signals at random moments: outputs whole or untouched, no orphans, no tracebacks.

- SIGTERM at random moments to ``train --out``, ``simulate --out``, ``listen --record`` and
  ``reproduce --out`` (``TRIES`` each: 5, or ``SKINHIL_SIGNAL_TRIES`` for a soak): every
  output is either the previous file, byte for byte, or a complete new one; no temporary
  file is left; no process the command started outlives it by more than 2 s
  (``reproduce --workers 2``).
- SIGINT 0-3 s after the start of each command (``TRIES // 4`` times, at least 2; counted
  from skinhil's first instruction, :func:`_main_started`): no traceback, exit status 0 (it
  had finished), 2 (refused) or 130.
- SIGTERM gives the summary where there is one (serve, demo, train, reproduce) and exit
  status 143.

Processes started by a command are found by an environment tag they inherit.
"""

from __future__ import annotations

import hashlib
import json
import os
import random
import select
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from harness.serve import RUN_DIR, serve_env

from skinhil.decoding import DirectionDecoder

TRIES = int(os.environ.get("SKINHIL_SIGNAL_TRIES", "5"))
"""SIGTERMs per command at random moments (5 by default; a soak: SKINHIL_SIGNAL_TRIES=50)."""
CLEAN_SIGINT = (0, 2, 130, -signal.SIGINT)
"""Exit statuses after a SIGINT: finished, refused, stopped; or ended by its default action
while the interpreter shut down after finishing (Python restores the default handlers then;
before skinhil's first instruction :func:`_main_started` sends none)."""
ORPHAN_GRACE_S = 2.0
REPRODUCE = ("reproduce", "--quick", "--workers", "2", "--grid", "2", "--repeats", "1",
             "--no-progress")


def _main_started(proc: subprocess.Popen[str], timeout_s: float = 30.0) -> None:
    """Wait until ``proc`` runs skinhil's code: it catches SIGTERM (``SigCgt`` in
    /proc/PID/status), which Python alone does not. Before that the interpreter is still
    starting (site-packages' .pth files): a SIGINT there is the interpreter's own,
    whatever the program."""
    bit = 1 << (signal.SIGTERM - 1)
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and proc.poll() is None:
        try:
            status = Path(f"/proc/{proc.pid}/status").read_text()
        except OSError:
            return
        caught = next(int(ln.split()[1], 16) for ln in status.splitlines()
                      if ln.startswith("SigCgt:"))
        if caught & bit:
            return
        time.sleep(0.002)


def _start(argv: list[str], tag: str, pass_fds: tuple[int, ...] = ()) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "skinhil", *argv], cwd=RUN_DIR,
                            env={**serve_env(), "SKINHIL_TEST_TAG": tag}, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, pass_fds=pass_fds)


def _read_ready(fd: int, timeout_s: float) -> dict[str, object]:
    """The ready line a process writes to the pipe ``fd`` (``--ready-fd``), read to the end
    of file it gives by closing its end."""
    end = time.monotonic() + timeout_s
    data = b""
    with os.fdopen(fd, "rb") as pipe:
        os.set_blocking(fd, False)
        while time.monotonic() < end:
            chunk = pipe.read()
            if chunk == b"":
                break
            data += chunk or b""
            time.sleep(0.05)
    assert data.endswith(b"\n") and data.count(b"\n") == 1, data
    return json.loads(data)


def _tagged(tag: str) -> list[int]:
    """Live processes carrying ``SKINHIL_TEST_TAG=tag`` in their environment."""
    needle = f"SKINHIL_TEST_TAG={tag}".encode()
    found = []
    for environ in Path("/proc").glob("[0-9]*/environ"):
        try:
            if needle in environ.read_bytes().split(b"\0"):
                stat = (environ.parent / "stat").read_text()
                if stat[stat.rfind(")") + 2:][:1] not in ("Z", "X"):
                    found.append(int(environ.parent.name))
        except OSError:
            continue
    return found


def _signal_at(argv: list[str], delay_s: float, signum: int = signal.SIGTERM,
               timeout_s: float = 90) -> tuple[int, str, str, list[int]]:
    """Run ``argv``, send ``signum`` ``delay_s`` (s) after skinhil's start unless it ended;
    (status, stdout,
    stderr, processes of its tag alive 2 s after it ended)."""
    tag = uuid.uuid4().hex
    proc = _start(argv, tag)
    _main_started(proc)
    try:
        proc.wait(timeout=delay_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signum)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    ended = time.monotonic()
    left = _tagged(tag)
    while left and time.monotonic() < ended + ORPHAN_GRACE_S:
        time.sleep(0.1)
        left = _tagged(tag)
    for pid in left:  # do not leave them to the next test
        os.kill(pid, signal.SIGKILL)
    return proc.returncode, out, err, left


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _npz_complete(keys: tuple[str, ...]) -> Callable[[Path], None]:
    def check(path: Path) -> None:
        with np.load(path, allow_pickle=False) as data:
            assert set(keys) <= set(data.files)
            for k in keys:
                data[k]  # noqa: B018  (reads and checks every entry's CRC)
    return check


def _decoder_complete(path: Path) -> None:
    DirectionDecoder.load(path)


@dataclass
class Output:
    """A command whose output file is checked: the argv writing ``path``."""

    name: str
    argv: list[str]
    path: Path
    complete: Callable[[Path], None]
    done: str
    """What its stdout says once it has finished."""


def _ended_ok(status: int, stdout: str, done: str) -> bool:
    """Finished (0), stopped (143), or ended by the SIGTERM's default action while the
    interpreter shut down after finishing (Python restores the default handlers then)."""
    return status in (0, 143) or (status == -signal.SIGTERM and done in stdout)


@pytest.fixture(scope="module")
def model_3x3(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "m3x3.npz"
    done = subprocess.run([sys.executable, "-m", "skinhil", "train", "--size", "3x3", "--reps",
                           "6", "--no-progress", "--out", str(path)], cwd=RUN_DIR,
                          env=serve_env(), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return path


def _kill_file_outputs(out: Output, rng: random.Random) -> list[str]:
    """TRIES SIGTERMs at random moments over one run's length; what went wrong."""
    t0 = time.monotonic()
    status, _, err, _ = _signal_at(out.argv, 600)  # the previous file, and the run's length
    assert status == 0, err
    length = time.monotonic() - t0
    problems = []
    for i in range(TRIES):
        before = _digest(out.path)
        status, stdout, err, left = _signal_at(out.argv, rng.uniform(0.0, 1.2 * length))
        if "Traceback" in err or not _ended_ok(status, stdout, out.done):
            problems.append(f"{out.name} try {i}: status {status}, {err[-300:]!r}")
        if left:
            problems.append(f"{out.name} try {i}: processes {left} outlived it")
        if _digest(out.path) != before:
            try:
                out.complete(out.path)
            except Exception as exc:  # noqa: BLE001 - reported below
                problems.append(f"{out.name} try {i}: a new but incomplete file: {exc!r}")
        partial = [p.name for p in out.path.parent.glob(".*partial*")]
        if partial:
            problems.append(f"{out.name} try {i}: temporary files left {partial}")
        if out.name == "train" and status == 143 and "training" in stdout:
            assert "the previous file kept" in stdout or "wrote" in stdout, stdout
    return problems


def _kill_reproduce(out_dir: Path, rng: random.Random) -> list[str]:
    """TRIES SIGTERMs 0.5-5 s into reproduce (its sweep workers run from ~3 s on)."""
    out_dir.mkdir()
    (out_dir / "REPORT.md").write_text("the previous report\n")
    (out_dir / "results.json").write_text("{}")
    problems = []
    for i in range(TRIES):
        before = {p.name: _digest(p) for p in out_dir.iterdir()}
        status, stdout, err, left = _signal_at([*REPRODUCE, "--out", str(out_dir)],
                                               rng.uniform(0.5, 5.0))
        if "Traceback" in err or not _ended_ok(status, stdout, "wrote"):
            problems.append(f"reproduce try {i}: status {status}, {err[-300:]!r}")
        if left:
            problems.append(f"reproduce try {i}: processes {left} outlived it by > 2 s")
        for p in out_dir.iterdir():
            if p.name.startswith("."):
                problems.append(f"reproduce try {i}: temporary file left {p.name}")
            elif before.get(p.name) != _digest(p):
                if p.suffix == ".json":
                    json.loads(p.read_text())
                elif p.suffix == ".png":
                    assert p.read_bytes()[-8:-4] == b"IEND", p
        if status == 143 and "stopped by SIGTERM" not in err:
            problems.append(f"reproduce try {i}: no stop line: {err[-200:]!r}")
    return problems


def test_sigterm_leaves_outputs_whole_and_no_orphans(tmp_path: Path, model_3x3: Path) -> None:
    rng = random.Random(18)
    outputs = [
        Output("simulate", ["simulate", "--size", "3x3", "--duration", "0.3", "--no-progress",
                            "--out", str(tmp_path / "run.npz")], tmp_path / "run.npz",
               _npz_complete(("forces_n", "events", "markers", "meta")), "wrote"),
        Output("train", ["train", "--size", "3x3", "--reps", "6", "--no-progress", "--out",
                         str(tmp_path / "dec.npz")], tmp_path / "dec.npz", _decoder_complete,
               "wrote"),
        Output("listen", ["listen", "--port", "loop://", "--size", "3x3", "--model",
                          str(model_3x3), "--duration", "0.5", "--record",
                          str(tmp_path / "session.npz")], tmp_path / "session.npz",
               _npz_complete(("events", "decisions", "markers", "meta")), "link:"),
    ]
    seeds = [rng.random() for _ in range(4)]
    jobs: list[Callable[[], list[str]]] = [
        *(lambda o=o, s=s: _kill_file_outputs(o, random.Random(s))
          for o, s in zip(outputs, seeds, strict=False)),
        lambda: _kill_reproduce(tmp_path / "repro", random.Random(seeds[3])),
    ]
    with ThreadPoolExecutor(2) as pool:
        problems = [p for job in list(pool.map(lambda j: j(), jobs)) for p in job]
    assert not problems, "\n".join(problems)


def test_sigint_in_the_first_3_s_gives_no_traceback(tmp_path: Path, model_3x3: Path) -> None:
    rng = random.Random(1830)
    commands = [
        ["serve", "--port", "loop://", "--duration", "5", "--quiet"],
        ["listen", "--port", "loop://", "--size", "3x3", "--model", str(model_3x3),
         "--duration", "5"],
        ["demo", "--model", str(model_3x3), "--duration", "5"],  # refused: another size
        ["train", "--size", "3x3", "--reps", "6", "--no-progress", "--out",
         str(tmp_path / "m.npz")],
        ["simulate", "--duration", "2", "--no-progress", "--out", str(tmp_path / "s.npz")],
        [*REPRODUCE, "--out", str(tmp_path / "repro")],
        ["compile"],
    ]
    runs = [(argv, rng.uniform(0.0, 3.0)) for argv in commands
            for _ in range(max(2, TRIES // 4))]
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda r: (r, _signal_at(r[0], r[1], signal.SIGINT)), runs))
    bad = [f"{argv[0]} at {delay:.2f} s: status {status}, {err[-400:]!r}"
           for (argv, delay), (status, _, err, left) in results
           if "Traceback" in err or status not in CLEAN_SIGINT or left]
    assert not bad, "\n".join(bad)


def _wait_for(proc: subprocess.Popen[str], stream: str, text: str, timeout_s: float) -> str:
    """Lines of ``proc``'s ``stream`` read until one holds ``text``."""
    end = time.monotonic() + timeout_s
    seen = []
    pipe = proc.stdout if stream == "stdout" else proc.stderr
    assert pipe is not None
    while time.monotonic() < end:
        line = pipe.readline()
        seen.append(line)
        if text in line or not line:
            break
    assert any(text in ln for ln in seen), seen
    return "".join(seen)


def _wait_for_bytes(proc: subprocess.Popen[str], text: str, timeout_s: float) -> None:
    """Read ``proc``'s stderr, unbuffered (a progress bar ends no line), until it holds
    ``text``."""
    assert proc.stderr is not None
    fd = proc.stderr.fileno()
    end = time.monotonic() + timeout_s
    seen = b""
    while time.monotonic() < end and text.encode() not in seen:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            chunk = os.read(fd, 4096)
            assert chunk, seen  # ended before it said so
            seen += chunk
    assert text.encode() in seen, seen


def test_sigterm_gives_the_summary_and_143(tmp_path: Path) -> None:
    read_end, write_end = os.pipe()
    serve = _start(["serve", "--port", "loop://", "--duration", "60", "--ready-fd",
                    str(write_end)], uuid.uuid4().hex, pass_fds=(write_end,))
    os.close(write_end)
    ready = _read_ready(read_end, 120)  # the ready line, without --json
    assert ready["type"] == "ready" and ready["pid"] == serve.pid, ready
    time.sleep(1.0)
    serve.send_signal(signal.SIGTERM)
    out, err = serve.communicate(timeout=30)
    assert serve.returncode == 143 and "served" in out and "Traceback" not in err, (out, err)

    repro = _start([*REPRODUCE, "--out", str(tmp_path / "repro")], uuid.uuid4().hex)
    time.sleep(8.0)  # in the sweeps
    repro.send_signal(signal.SIGTERM)
    out, err = repro.communicate(timeout=30)
    assert repro.returncode == 143, (out, err)
    assert "reproduce: stopped after" in out and "Traceback" not in err, (out, err)

    train = _start(["train", "--reps", "200", "--out", str(tmp_path / "m.npz")],
                   uuid.uuid4().hex)
    _wait_for_bytes(train, "simulating the board stream", 120)  # its progress bar: training
    time.sleep(1.0)
    train.send_signal(signal.SIGTERM)
    out, err = train.communicate(timeout=30)
    assert train.returncode == 143, (out, err)
    assert "train: stopped after" in out and "nothing written" in out, (out, err)
    assert not (tmp_path / "m.npz").exists()


def test_demo_sigterm_prints_the_figures_so_far(tmp_path: Path) -> None:
    model = tmp_path / "m.npz"
    done = subprocess.run([sys.executable, "-m", "skinhil", "train", "--reps", "6",
                           "--no-progress", "--out", str(model)], cwd=RUN_DIR,
                          env=serve_env(), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    demo = _start(["demo", "--model", str(model), "--duration", "60"], uuid.uuid4().hex)
    _wait_for(demo, "stdout", "receiver:", 120)
    time.sleep(3.0)
    demo.send_signal(signal.SIGTERM)
    out, err = demo.communicate(timeout=30)
    assert demo.returncode == 143, (out, err)
    assert "demo: stopped after" in out and "link:" in out and "Traceback" not in err, out


def test_sigint_inside_a_compiled_functions_callback_stops_cleanly_after_it() -> None:
    """A SIGINT while a compiled function calls back into Python (numba's unpickler, as it
    returns an array) is delivered once it has returned: the call completes and the stop
    comes as :class:`Stopped`, not as "SystemError: ... returned a result with an exception
    set" (what ``simulate`` ended with when the signal was handled inside the callback)."""
    from skinhil.cli import signals
    from skinhil.model.neurons import raster_to_events

    raster = np.zeros((10, 338), dtype=np.bool_)
    raster[3, 7] = True
    raster_to_events(raster, 1e-4)  # compiled (or loaded) before the signal
    sent: list[str] = []

    def send_in_callback(frame, event, arg):  # type: ignore[no-untyped-def]
        if event == "call" and frame.f_code.co_name == "_numba_unpickle" and not sent:
            sent.append(frame.f_code.co_filename)
            os.kill(os.getpid(), signal.SIGINT)  # handled at the callback's next bytecode

    old = signals.install()
    signals.resume()
    events = None
    try:
        with pytest.raises(signals.Stopped):
            sys.setprofile(send_in_callback)
            try:
                events = raster_to_events(raster, 1e-4)
            finally:
                sys.setprofile(None)
            time.sleep(5 * signals.RESEND_S + 1.0)  # the signal delivered again meanwhile
    finally:
        signals.finish()
        signals.restore(old)
    assert sent, "the compiled call made no callback to numba's unpickler"
    assert events is not None and events["addr"].tolist() == [7]
