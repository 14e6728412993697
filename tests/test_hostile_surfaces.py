"""The surfaces a hostile user tried (issue 43): grip truth files, campaigns, injected faults,
hang-ups, scenario files, stdout that cannot be written.

Each row of :func:`_refusals` is one input of a class, refused with one ``skinhil: error:``
line and exit status 2 (run through :func:`skinhil.cli.main` in this process: none needs a
board). The files a refusal protects are checked byte for byte. The bench's run-time
findings run as a user runs them: ``--faults drop_p=1`` is the rig's error with its reason in
the summary and the JUnit XML; SIGHUP and SIGKILL of ``bench`` mid-case leave no process
behind.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from harness.refusals import refusal_failures
from harness.serve import REPO, RUN_DIR, serve_argv, serve_env

import protocols
from skinhil.campaign import campaign_file
from skinhil.campaign.campaign_file import load_campaign
from skinhil.campaign.relay import RelayLink
from skinhil.campaign.rig import RigBounds, rig_faults
from skinhil.cli import main
from skinhil.cli.signals import STOP_SIGNALS, _descendants
from skinhil.errors import ConfigError
from skinhil.plant import HELD_DTYPE
from skinhil.plant.truth_file import MAGIC, HeldTruthReader, HeldTruthWriter
from skinhil.transports.faults import FaultParams

PRESS = REPO / "examples" / "scenarios" / "press.toml"
CONTACT_HEAD = '[[indenter]]\nname = "s"\nshape = "sphere"\nradius_mm = 2.0\n'

STIMULUS = '[[stimulus]]\nname = "{}"\nforces = {{ 15 = [0, 0, -0.1] }}\n'
EVENT = '[[event]]\nstart_s = 0\nstimulus = "p"\n'


def _contact(body: str) -> str:
    return f'{CONTACT_HEAD}[[contact]]\nindenter = "s"\n{body}'


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]
    word: str
    """A word the error line says (case-insensitive)."""


SCENARIOS: dict[str, tuple[str, str]] = {
    # name: (scenario text, a word of the refusal)
    "two indenters of one name": (CONTACT_HEAD + CONTACT_HEAD + _contact(
        'motion = "press"\ndepth_mm = 0.2\n')[len(CONTACT_HEAD):], "distinct"),
    "taps not whole": (_contact('motion = "tap"\ndepth_mm = 0.05\ntaps = 2.5\n'
                                'period_s = 0.1\ncontact_s = 0.03\n'), "taps"),
    "taps past a trajectory": (_contact('motion = "tap"\ndepth_mm = 0.05\ntaps = 5000\n'
                                        'period_s = 0.1\ncontact_s = 0.03\n'), "taps"),
    "press off the skin": (_contact('motion = "press"\nx_mm = 50.0\ny_mm = -50.0\n'
                                    'depth_mm = 0.2\n'), "never"),
    "slide beside the skin": (_contact('motion = "slide"\nx_mm = -90.0\ny_mm = 40.0\n'
                                       'to_x_mm = 90.0\nto_y_mm = 40.0\n'
                                       'speed_mm_per_s = 50.0\ndepth_mm = 0.2\n'), "never"),
    "key of another shape": ('[[indenter]]\nname = "s"\nshape = "sphere"\nradius_mm = 2.0\n'
                             'width_mm = 1.0\n[[contact]]\nindenter = "s"\nmotion = "press"\n'
                             'depth_mm = 0.2\n', "width_mm"),
    "two stimuli of one name": (STIMULUS.format("p") + STIMULUS.format("p") + EVENT,
                                "taken"),
    "a stimulus named like a built-in": (STIMULUS.format("A") + EVENT.replace('"p"', '"A"'),
                                         "built-in"),
    "path time 1e300 s": (_contact('motion = "path"\npath = [[0, 0, 0, 0.1], '
                                   '[1e300, 0, 0, 0.1]]\n'), "path times"),
    "two contacts of one name": (CONTACT_HEAD + ('[[contact]]\nindenter = "s"\nname = "c"\n'
                                                 'motion = "press"\ndepth_mm = 0.2\n') * 2,
                                 "distinct"),
    "a path's depth_mm besides its keyframes": (_contact(
        'motion = "path"\ndepth_mm = 0.3\npath = [[0, 0.5, 0.5, 0.1]]\n'), "depth_mm"),
    "vibration_hz without vibration_mm": (_contact(
        'motion = "press"\ndepth_mm = 0.2\nvibration_hz = 100.0\n'), "vibration_mm"),
}

CAMPAIGNS: dict[str, tuple[str, str]] = {
    "seed past the top with repetitions": (
        'name = "c"\nrepetitions = 2\n[parameters]\nseed = 9223372036854775807\n'
        '[[scenario]]\nbuiltin = "random"\n', "seed"),
    "scenario a symlink loop": ('name = "c"\n[[scenario]]\nfile = "loop.toml"\n', "loop"),
    "scenario path with a NUL": ('name = "c"\n[[scenario]]\nfile = "a\\u0000b"\n', "path"),
    "size past the wire": ('name = "c"\n[parameters]\nsize = "300x300"\n[[scenario]]\n'
                           'builtin = "random"\n', "sensors"),
    "size 2x2": ('name = "c"\n[parameters]\nsize = "2x2"\n[[scenario]]\n'
                 'builtin = "random"\n', "campaign file"),
}


def _refusals(tmp: Path) -> list[Case]:
    os.symlink("loop.toml", tmp / "loop.toml")
    cases = []
    for name, (text, word) in SCENARIOS.items():
        path = tmp / f"{len(cases)}.toml"
        path.write_text(text, encoding="utf-8")
        cases.append(Case(f"scenario: {name}", ("stimuli", "--schedule", str(path)), word))
    for name, (text, word) in CAMPAIGNS.items():
        path = tmp / f"campaign{len(cases)}.toml"
        path.write_text(text, encoding="utf-8")
        cases.append(Case(f"campaign: {name}", ("bench", str(path), "--out",
                                                str(tmp / "out")), word))
    smoke = str(REPO / "examples" / "campaigns" / "smoke.toml")
    cases += [
        Case("bench --faults twice", ("bench", smoke, "--faults", "drop_p=1", "--faults",
                                      "drop_p=0"), "twice"),
        Case("bench --faults seed=-1", ("bench", smoke, "--faults", "seed=-1", "--out",
                                        str(tmp / "seed")), "seed"),
        Case("bench --out uncreatable", ("bench", smoke, "--model", str(_model(tmp)), "--out",
                                         "/proc/self/nope/out"), "cannot be created"),
        # refused before a model is trained (the model cache is unwritable here: a model
        # looked for first is refused for that instead)
        Case("bench --out under a file", ("bench", smoke, "--out", str(tmp / "0.toml" / "o")),
             "is not a folder"),
        Case("bench --suite --out under a file", ("bench", "--suite", "tactile-v1", "--out",
                                                  str(tmp / "0.toml" / "o")), "is not a folder"),
        Case("serve --grasp-truth a foreign file",
             ("serve", "--link", "pty:", "--grasp", "1", "--grasp-truth",
              str(tmp / "decoder.npz")), "not a held-object truth file"),
    ]
    return cases


def test_hostile_inputs_refused_in_one_line(tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", "/proc/nope")
    foreign = tmp_path / "decoder.npz"
    foreign.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 64)
    before = foreign.read_bytes()
    failures = refusal_failures(_refusals(tmp_path), capsys)
    assert not failures, "\n".join(failures)
    assert foreign.read_bytes() == before  # refused, never truncated
    assert not (tmp_path / "seed").exists() and not (tmp_path / "out" / "cases").exists()


def test_stimuli_schedule_takes_a_scenario_file_and_names_its_contacts(capsys) -> None:
    assert main(["stimuli", "--schedule", str(PRESS), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["contacts"] == ["contact0"] and out["n_stimuli"] >= 1


def _records(n: int, t0: int) -> np.ndarray:
    r = np.zeros(n, dtype=HELD_DTYPE)
    r["t_us"] = t0 + np.arange(n) * 1000
    r["grip_n"] = 0.3
    return r


def test_grasp_truth_appends_to_its_own_file_and_refuses_others(tmp_path: Path) -> None:
    """A second run appends to the first run's file (nothing of it lost), a torn end is cut
    to whole records, a read-only truth file and a foreign file are refused in one line."""
    path = tmp_path / "held.bin"
    for t0 in (0, 10_000_000):
        writer = HeldTruthWriter(path)
        for row in _records(120, t0):
            writer.add(row[None])
        writer.close()
    got = HeldTruthReader(path).read()
    assert path.read_bytes()[:len(MAGIC)] == MAGIC
    assert np.array_equal(got, np.concatenate([_records(120, 0), _records(120, 10_000_000)]))
    with path.open("ab") as f:  # a run ended inside a write
        f.write(b"\x01" * 7)
    HeldTruthWriter(path).close()
    assert len(HeldTruthReader(path).read()) == 240
    path.chmod(0o444)
    try:
        if os.geteuid() != 0:
            with pytest.raises(ConfigError, match="read-only"):
                HeldTruthWriter(path)
    finally:
        path.chmod(0o644)
    foreign = tmp_path / "notes.txt"
    foreign.write_text("my notes\n")
    with pytest.raises(ConfigError, match="not a held-object truth file"):
        HeldTruthWriter(foreign)
    assert foreign.read_text() == "my notes\n"


def test_case_ids_keep_exact_values_and_scenarios_load_once(tmp_path: Path,
                                                           monkeypatch) -> None:
    """Values that differ past 6 digits give two ids; a campaign of 10,000 cases over one
    scenario file 100 times reads the file once per skin size, not once per scenario."""
    path = tmp_path / "c.toml"
    path.write_text('name = "c"\n[parameters]\nduration_s = [1.0, 1.0000001]\n'
                    '[[scenario]]\nbuiltin = "random"\n', encoding="utf-8")
    ids = [c.id for c in load_campaign(path).cases()]
    assert len(set(ids)) == 2 and ids[0] == "random[duration_s=1]#1", ids
    reads = []
    real = campaign_file.load_scenario
    monkeypatch.setattr(campaign_file, "load_scenario",
                        lambda *a: reads.append(a) or real(*a))
    scenarios = "".join(f'[[scenario]]\nname = "s{i}"\nfile = "{PRESS}"\n' for i in range(100))
    path.write_text('name = "c"\n[parameters]\nduration_s = ['
                    + ", ".join(f"{0.5 + i / 100:g}" for i in range(100)) + "]\n" + scenarios,
                    encoding="utf-8")
    assert len(load_campaign(path).cases()) == 10_000
    assert len(reads) == 1


@pytest.mark.parametrize("faults", [FaultParams(drop_p=1.0),
                                    FaultParams(delay_p=1.0, delay_s=1e9)],
                         ids=["drop_p=1", "delay_s=1e9"])
def test_injected_faults_the_decoder_never_sees_are_the_rigs_error(
        faults: FaultParams) -> None:
    """Frames the relay dropped or held past the run show no sequence gap to the tap (they
    are the last ones): the rig still counts them, and says the decoder received nothing."""
    relay = RelayLink(921_600, faults)
    with relay:
        fd = os.open(relay.board_path, os.O_RDWR | os.O_NOCTTY)
        try:
            os.write(fd, b"\x05\x01\x02\x03\x00" * 20)
            end = time.monotonic() + 5
            while relay.counters()["injected"]["units_seen"] < 20 and time.monotonic() < end:
                time.sleep(0.02)
        finally:
            os.close(fd)
    tap = relay.counters()
    assert tap["injected"]["units_seen"] == 20 and tap["frames_ok"] == 0
    faults_seen = rig_faults(RigBounds(), None, tap)
    assert any("received nothing" in f for f in faults_seen), faults_seen
    assert any("20 frames" in f for f in faults_seen), faults_seen


def _model(tmp: Path) -> Path:
    from skinhil.decoding.classifier import DirectionDecoder
    from skinhil.decoding.model_file import save_decoder
    from skinhil.receiver.training import feature_spec

    spec = feature_spec()
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(36, spec.n_features)), np.repeat(np.arange(9), 4)
    path = tmp / "model.npz"
    save_decoder(DirectionDecoder(spec).fit(x, y), path)
    return path


def _campaign(tmp: Path, duration_s: float) -> Path:
    path = tmp / "one.toml"
    path.write_text(f'name = "one"\ncriteria = ["decisions >= 0"]\n[parameters]\n'
                    f'duration_s = {duration_s}\n[[scenario]]\nbuiltin = "random"\n'
                    '[rig]\nmax_lateness_ms = 5000.0\n', encoding="utf-8")
    return path


def _bench(tmp: Path, duration_s: float, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "skinhil", "bench",
                             str(_campaign(tmp, duration_s)), "--quiet", "--model",
                             str(_model(tmp)), "--out", str(tmp / "out"), *args],
                            cwd=RUN_DIR, env=serve_env(), text=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)


def test_bench_with_drop_p_1_is_the_rigs_error_with_its_reason(tmp_path: Path) -> None:
    proc = _bench(tmp_path, 0.5, "--faults", "drop_p=1")
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 1, err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    (case,) = summary["cases"]
    assert case["outcome"] == "error" and "received nothing" in case["message"], case
    junit = (tmp_path / "out" / "junit.xml").read_text(encoding="utf-8")
    assert "<error" in junit and "received nothing" in junit


def _case_started(proc: subprocess.Popen[str], timeout_s: float = 240) -> list[int]:
    """Wait until bench runs its board (a case under way); its descendants then."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and proc.poll() is None:
        kids = _descendants(proc.pid)
        for pid in kids:
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if b"serve" in cmd.split(b"\x00"):
                time.sleep(0.5)  # the board past its start
                return _descendants(proc.pid)
        time.sleep(0.1)
    pytest.fail(f"bench started no board: {proc.poll()}")


def _gone(pids: list[int], timeout_s: float = 15) -> list[int]:
    end = time.monotonic() + timeout_s
    alive = pids
    while alive and time.monotonic() < end:
        alive = [p for p in alive if _running(p)]
        time.sleep(0.1)
    return alive


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return state[state.rfind(")") + 2:][:1] not in ("Z", "X")


@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGKILL], ids=["SIGHUP", "SIGKILL"])
def test_a_signal_to_bench_mid_case_leaves_no_process(tmp_path: Path, signum: int) -> None:
    assert signal.SIGHUP in STOP_SIGNALS
    proc = _bench(tmp_path, 30.0)
    try:
        kids = _case_started(proc)
        assert kids
        os.kill(proc.pid, signum)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == (129 if signum == signal.SIGHUP else -signal.SIGKILL)
    assert _gone(kids) == []


@pytest.mark.parametrize("argv,redirect", [(["stimuli"], "> /dev/full"),
                                           (["pty"], "1>&-")], ids=["full", "closed"])
def test_stdout_that_cannot_be_written_is_one_line(argv: list[str], redirect: str) -> None:
    cmd = " ".join([sys.executable, "-m", "skinhil", *argv]) + " " + redirect
    done = subprocess.run(cmd, shell=True, cwd=RUN_DIR, env=serve_env(), text=True,
                          stderr=subprocess.PIPE, timeout=60, stdin=subprocess.DEVNULL)
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert done.returncode in (1, 2) and len(lines) == 1, done.stderr
    assert lines[0].startswith("skinhil: error: ")


def test_a_stop_in_an_import_locks_callback_is_delivered_again() -> None:
    """The import system's weakref callback (``cb`` in ``<frozen importlib._bootstrap>``)
    loses an exception raised in it: a signal there is sent again instead."""
    from skinhil.cli.signals import _in_native_callback

    namespace: dict[str, object] = {"sys": sys}
    exec(compile("def cb(ref=None):\n    return sys._getframe()\n",
                 "<frozen importlib._bootstrap>", "exec"), namespace)
    frame = namespace["cb"]()  # type: ignore[operator]
    assert _in_native_callback(frame)
    assert not _in_native_callback(sys._getframe())


def test_a_stop_during_a_held_write_is_raised_after_it() -> None:
    """Inside :func:`signals.held` a SIGTERM is only recorded; it raises as the write
    ends."""
    from skinhil.cli import signals

    previous = signals.install()
    try:
        signals.resume()
        done = []
        with pytest.raises(signals.Stopped):
            with signals.held():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)
                done.append(True)
        assert done == [True]
    finally:
        signals.restore(previous)
        signals._received.clear()


def test_a_replay_counts_every_refused_host_unit(tmp_path: Path) -> None:
    """Host units sent while a recording plays: commands (NACKed REPLAYING), a corrupted
    packet, a repeated sequence number and a host's SYNC + EVENTS are each one refused unit
    in the replay summary, as a board's STATUS counts them (SPEC.md §3.3)."""
    from conftest import PtyReader

    from protocols.capture import CaptureHeader, CaptureWriter
    from protocols.events import make_events
    from skinhil.recording import Replayer, open_recording
    from skinhil.transports import PtyMasterTransport

    enc = protocols.SerialEncoder()
    rec = tmp_path / "r.skcap"
    with rec.open("wb") as f:
        w = CaptureWriter(f, CaptureHeader(3, "serial", 100, 0))
        for k in range(20):  # 0.4 s of events, 20 ms apart
            w.write(k * 20_000_000, k * 20_000, enc.events(
                make_events(np.array([k * 20_000]), np.array([k])), (k + 1) * 20_000))
        w.close(20 * 20_000_000)
    host = protocols.SerialEncoder()
    ping = [host.command(protocols.Command(token=t, opcode=protocols.CommandCode.PING))
            for t in (1, 2, 3)]
    decision = host.command(protocols.Decision(token=4, stimulus_id=0, confidence=1.0))
    corrupted = bytearray(host.command(protocols.Command(token=5,
                                                         opcode=protocols.CommandCode.PING)))
    corrupted[4] ^= 0x10
    sync_and_events = host.events(make_events(np.array([100]), np.array([3])), 1000)
    units = (ping[0], ping[1], decision, bytes(corrupted), ping[2], ping[2], sync_and_events)
    refused = 2 + 1 + 1 + 2 + 2  # NACKs, the CRC error, PING 3 and its repeat, SYNC + EVENTS

    link, slave = PtyMasterTransport.open_pair()
    reader = PtyReader(slave)
    try:
        os.write(slave, b"".join(units))
        summary = Replayer(open_recording(rec), link).run()
        time.sleep(0.2)
        back = protocols.SerialDecoder().feed(reader.take())
    finally:
        reader.stop()
        link.shutdown()
        os.close(slave)
    acks = [r for r in back.records if isinstance(r, protocols.Ack)]
    assert [(a.token, a.reason) for a in acks] == [
        (t, protocols.NackReason.REPLAYING) for t in (1, 2, 4, 3)]
    assert summary.complete and summary.commands == 4
    assert summary.rx_errors == refused, summary


@pytest.fixture(scope="module")
def warm_kernels() -> None:
    """Kernels compiled before a command whose stderr is counted (a cold cache adds a
    notice line)."""
    done = subprocess.run([sys.executable, "-m", "skinhil", "compile"], cwd=RUN_DIR,
                          env=serve_env(), capture_output=True, text=True, timeout=600,
                          stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr


@pytest.fixture
def full_folder(tmp_path: Path) -> Iterator[Path]:
    """A folder on an 8 KiB tmpfs (mounted here: needs root), unmounted after the test."""
    folder = tmp_path / "small"
    folder.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8k", "tmpfs", str(folder)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (not root)")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True)


def test_record_onto_a_full_disk_is_one_error_line_and_the_run_still_ends(
        full_folder: Path, warm_kernels: None) -> None:
    """``serve --record`` onto a disk that fills: one ``skinhil: error:`` line, a non-zero
    status, no partial file, and the receiver still gets the board's RUN_END."""
    from conftest import PtyPair, PtyReader

    pair = PtyPair()
    reader = PtyReader(pair.master)
    try:
        done = subprocess.run(serve_argv("--port", pair.path, "--record",
                                         str(full_folder / "run.skcap"), "--duration", "20",
                                         "--quiet"), cwd=RUN_DIR, env=serve_env(), text=True,
                              capture_output=True, timeout=120, stdin=subprocess.DEVNULL)
        time.sleep(0.3)
        stream = protocols.SerialDecoder().feed(reader.take())
    finally:
        reader.stop()
        pair.close()
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert done.returncode != 0 and len(lines) == 1, done.stderr
    assert lines[0].startswith("skinhil: error: ") and "space" in lines[0], lines
    assert any(isinstance(r, protocols.RunEnd) for r in stream.records)
    assert list(full_folder.iterdir()) == []


def test_a_decoder_stored_big_endian_is_the_same_decoder(tmp_path: Path, capsys) -> None:
    """Every array of a decoder file in big-endian byte order (its digest taken as stored):
    read as the same decoder, which decides as the original does; arrays of another type are
    refused naming it."""
    from harness.hostile_models import _entries, _signed, _write, write_good

    from skinhil.decoding import DirectionDecoder

    good = write_good(tmp_path / "good.npz")
    header, arrays = _entries(good)
    swapped = {k: a.astype(a.dtype.newbyteorder(">")) for k, a in arrays.items()}
    assert all(a.dtype.byteorder == ">" for a in swapped.values())
    _write(tmp_path / "big.npz", _signed(header, swapped), swapped)
    ours, theirs = DirectionDecoder.load(good), DirectionDecoder.load(tmp_path / "big.npz")
    x = np.random.default_rng(1).normal(size=(50, ours.spec_.n_features))
    assert np.array_equal(ours.predict(x), theirs.predict(x))
    assert np.array_equal(ours.coef_, theirs.coef_)
    single = {**arrays, "coef": arrays["coef"].astype(">f4")}
    _write(tmp_path / "f4.npz", _signed(header, single), single)
    refuse = Case("float32 coef", ("listen", "--port", "loop://", "--model",
                                   str(tmp_path / "f4.npz")), "holds float32")
    failures = refusal_failures([refuse], capsys)
    assert not failures, failures


def test_a_killed_demo_leaves_no_temp_folder_after_the_next_start(
        tmp_path: Path, warm_kernels: None) -> None:
    """``demo`` killed by SIGKILL mid-run cannot remove its temporary folder (its board dies
    with it); the next ``demo`` removes it, and its own, and leaves nothing in the system's
    temporary folder."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {**serve_env(), "TMPDIR": str(tmp)}
    demo = [sys.executable, "-m", "skinhil", "demo", "--model", str(_model(tmp_path)),
            "--quiet", "--duration"]
    proc = subprocess.Popen([*demo, "60"], cwd=RUN_DIR, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    try:
        kids = _case_started(proc)
        left = [p for p in tmp.rglob("*") if p.is_dir()]
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert _gone(kids) == []
    assert left and all(p.exists() for p in left)  # what the killed demo could not remove
    done = subprocess.run([*demo, "1"], cwd=RUN_DIR, env=env, text=True, capture_output=True,
                          timeout=180, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    remains = sorted(str(p.relative_to(tmp)) for p in tmp.rglob("*"))
    assert remains in ([], [f"skinhil-{os.getuid()}"]), remains


def test_only_folders_of_ended_processes_are_removed(tmp_path: Path, monkeypatch) -> None:
    """A folder of this process, of a pid reused by another process (another start time) and
    of a pid that does not run; and a name not of skinhil's: only the ended ones go."""
    from skinhil import temp_folders

    monkeypatch.setattr(temp_folders.tempfile, "gettempdir", lambda: str(tmp_path))
    with temp_folders.TempFolder("mine") as mine:
        parent = mine.parent
        ticks = temp_folders._start_ticks(os.getpid())
        assert ticks
        reused = parent / f"{os.getpid()}-{ticks + 1}-demo-0"
        ended = parent / f"{2**22 + 1}-5-demo-0"
        foreign = parent / "notes"
        for p in (reused, ended, foreign):
            p.mkdir()
        with temp_folders.TempFolder("next") as other:
            assert sorted(p.name for p in parent.iterdir()) == sorted(
                [mine.name, other.name, "notes"])
        assert not other.exists() and mine.exists()
    assert not mine.exists() and parent.stat().st_mode & 0o777 == 0o700


def test_grasp_truth_onto_a_full_disk_keeps_the_run_and_ends_in_one_line(
        full_folder: Path, tmp_path: Path, warm_kernels: None) -> None:
    """``serve --grasp --grasp-truth`` onto a disk that fills: the run plays to its end (its
    score written), the truth file holds whole records only, and the run ends with one
    ``skinhil: error:`` line saying how far the file got, status 2."""
    truth, score = full_folder / "held.bin", tmp_path / "score.json"
    done = subprocess.run(serve_argv("--port", "loop://", "--grasp", "3", "--grasp-truth",
                                     str(truth), "--score", str(score), "--quiet"),
                          cwd=RUN_DIR, env=serve_env(), text=True, capture_output=True,
                          timeout=120, stdin=subprocess.DEVNULL)
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("skinhil: error: ") and "space" in lines[0], lines
    assert json.loads(score.read_text(encoding="utf-8"))["grasp"]["lifts"] == 3
    kept = HeldTruthReader(truth).read()
    assert len(kept) and truth.stat().st_size == len(MAGIC) + kept.nbytes
    assert f"after {len(kept)} records" in lines[0]


def test_a_killed_recorders_spool_is_removed_by_the_next(tmp_path: Path) -> None:
    """``listen --record``'s event spool beside the output: one left by an ended process is
    removed when the next recorder starts in that folder; a live one and other files stay."""
    from skinhil.recording import SessionRecorder
    from skinhil.recording.session import SPOOL_PREFIX
    from skinhil.temp_folders import process_tag

    stale = tmp_path / f"{SPOOL_PREFIX}{2**22 + 1}-7.abc.spool"
    live = tmp_path / f"{SPOOL_PREFIX}{process_tag()}.xyz.spool"
    other = tmp_path / f"{SPOOL_PREFIX}notes.spool"
    for p in (stale, live, other):
        p.write_bytes(b"x")
    with SessionRecorder(tmp_path):
        names = sorted(p.name for p in tmp_path.iterdir())
        assert stale.name not in names and live.exists() and other.exists()
        assert len(names) == 3  # its own spool beside the two kept
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, other.name])
