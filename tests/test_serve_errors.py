"""Bad input to ``skinhil serve``: one clear line on stderr, a non-zero exit, no traceback."""

from __future__ import annotations

import os
import shutil
import subprocess

import pytest
import serial
from conftest import HAS_VCAN
from harness.serve import RUN_DIR, serve_argv, serve_env

_DROP_DAC = ["setpriv", "--bounding-set", "-dac_override,-dac_read_search",
             "--inh-caps", "-dac_override,-dac_read_search"]


def _no_nice_prefix() -> list[str]:
    """A command prefix without CAP_SYS_NICE (root) so --realtime is refused."""
    if os.geteuid() != 0:
        return []
    if shutil.which("setpriv") is None:
        pytest.fail("running as root: need setpriv (util-linux) to test a refused --realtime")
    return ["setpriv", "--bounding-set", "-sys_nice", "--inh-caps", "-sys_nice"]


def _start(argv: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(argv, cwd=RUN_DIR, env=serve_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _one_error_line(proc: subprocess.Popen[str]) -> str:
    out, err = proc.communicate(timeout=60)
    assert proc.returncode not in (0, None), (out, err)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in err, err
    assert len(lines) == 1 and lines[0].startswith("skinhil: error: "), err
    return lines[0]


def test_serve_bad_input_errors(tmp_path, pty_pair) -> None:
    bad_toml = tmp_path / "bad.toml"
    bad_toml.write_text("[[event]]\nstart_s = 'soon'\nstimulus = 'A'\n")
    unknown_stim = tmp_path / "unknown.toml"
    unknown_stim.write_text("[[event]]\nstart_s = 0.5\nstimulus = 'nope'\n")
    busy = serial.serial_for_url(pty_pair.path, 921600, exclusive=True)  # holds the lock
    denied = os.openpty()
    denied_path = os.ttyname(denied[1])
    os.chmod(denied_path, 0)
    prefix = _DROP_DAC if os.geteuid() == 0 else []
    if prefix and shutil.which("setpriv") is None:
        pytest.fail("running as root: need setpriv (util-linux) to test a not-permitted port")
    cases = {
        "missing": (serve_argv("--port", str(tmp_path / "ttyNOPE")), "not found"),
        "busy": (serve_argv("--port", pty_pair.path), "busy"),
        "denied": (prefix + serve_argv("--port", denied_path), "permission denied"),
        "baud": (serve_argv("--port", pty_pair.path, "--baud", "-5"), "invalid baud"),
        "bitrate": (serve_argv("--can", "vcan0", "--bitrate", "7"), "invalid CAN bitrate"),
        "toml": (serve_argv("--port", "loop://", "--schedule", str(bad_toml)), "start_s"),
        "stim": (serve_argv("--port", "loop://", "--schedule", str(unknown_stim)),
                 "unknown stimulus"),
        "nofile": (serve_argv("--port", "loop://", "--schedule", str(tmp_path / "x.toml")),
                   "not found"),
        "can": (serve_argv("--can", "vcan9"),
                "does not exist" if HAS_VCAN else "no SocketCAN support"),
        "board": (serve_argv("--port", "loop://", "--board-id", "99"), "--board-id"),
        "threads": (serve_argv("--port", "loop://", "--threads", "0"), "--threads"),
        "realtime": (_no_nice_prefix() + serve_argv("--port", "loop://", "--realtime",
                                                    "--duration", "0.1"), "real-time"),
    }
    try:
        procs = {name: _start(argv) for name, (argv, _) in cases.items()}
        for name, proc in procs.items():
            line = _one_error_line(proc)
            assert cases[name][1].lower() in line.lower(), (name, line)
            if name == "can":
                assert "ip link add dev vcan0 type vcan" in line
    finally:
        busy.close()
        for fd in denied:
            os.close(fd)


@pytest.mark.vcan
def test_serve_unknown_can_channel_on_a_can_system() -> None:
    line = _one_error_line(_start(serve_argv("--can", "vcan9", "--duration", "1")))
    assert "vcan9" in line and "does not exist" in line and "type vcan" in line
