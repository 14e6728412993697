"""Run a command inside user-mode Linux (UML) where a real ``vcan0`` exists.

This host's kernel may lack CAN (``socket.AF_CAN`` fails). Debian's ``user-mode-linux``
package ships a kernel that runs as a normal process and has the CAN modules; booted with
``rootfstype=hostfs`` it sees this machine's files, so the same Python, the same repository
and the same installed packages run inside it. The init script written here mounts /proc
and /sys, loads can.ko, can-raw.ko, can-dev.ko and vcan.ko, creates ``vcan0`` and
``vcan1``, runs the command in the given directory, writes its exit status and output to
files on the host and powers the UML machine off.

Needs (Debian): ``apt-get install -y user-mode-linux kmod iproute2``.

Use from the command line (prints the command's output, exits with its status)::

    python tests/uml_vcan.py -- python -m pytest -m vcan tests

Memory: UML backs its RAM with a file mapped page by page into the host processes that
run its programs, so a UML program with a large resident set needs one host mapping per
scattered page: past the host's ``vm.max_map_count`` (65530 by default, about 600 MB of
scattered resident memory in one UML program) the host ``mmap`` fails with ENOMEM and UML
kills the program ("UML ran out of memory on the host side"). :func:`run_in_uml` reports
that case in :attr:`UmlResult.host_maps_exhausted`; run big suites one test file per boot,
or raise the limit (``sysctl -w vm.max_map_count=262144``). Boot to the init script takes
about 1.5-2.8 s here; importing numpy inside takes about 1 s and every system call is
slow, so use it for correctness at moderate rates.
"""

from __future__ import annotations

import argparse
import dataclasses
import gzip
import lzma
import os
import platform
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

UML_KERNEL = "linux"
"""Name of Debian's user-mode Linux kernel binary on PATH."""
UML_MODULES_ROOT = Path("/usr/lib/uml/modules")
CAN_MODULES = ("can", "can-raw", "can-dev", "vcan")
"""Modules to load, in dependency order."""
IN_UML_ENV = "SKINHIL_IN_UML"
"""Set to "1" in the environment of the command run inside UML."""
PASSED_ENV = ("HOME", "LANG", "LC_ALL", "VIRTUAL_ENV", "PYTHONHASHSEED", "NUMBA_CACHE_DIR",
              "NUMBA_DISABLE_JIT", "NUMBA_NUM_THREADS", "TZ")
"""Environment variables copied from the caller into the UML command's environment."""


class UmlUnavailable(RuntimeError):
    """User-mode Linux, its CAN modules or the tools to set up vcan0 are missing."""


@dataclasses.dataclass(frozen=True)
class UmlResult:
    """Outcome of :func:`run_in_uml`.

    ``returncode`` is the command's exit status inside UML (None if it never reported one),
    ``output`` its stdout+stderr, ``boot_s`` the wall time (s) from starting the kernel to the
    init script running, ``command_s`` the command's own wall time (s), ``total_s`` the
    whole run, ``console`` the UML kernel's console log.
    """

    returncode: int | None
    output: str
    boot_s: float | None
    command_s: float | None
    total_s: float
    console: str

    @property
    def host_maps_exhausted(self) -> bool:
        """True if UML hit the host's ``vm.max_map_count`` (a program was killed for it)."""
        return "vm.max_map_count has been reached" in self.console \
            or "ran out of memory on the host side" in self.console


def host_has_can(channel: str = "vcan0") -> bool:
    """True if this kernel has SocketCAN and a CAN interface named ``channel`` is up."""
    if not hasattr(socket, "AF_CAN"):
        return False
    try:
        with socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as s:
            s.bind((channel,))
    except OSError:
        return False
    return True


def host_max_map_count() -> int | None:
    """This host's ``vm.max_map_count`` (mappings per process), None if unknown."""
    try:
        return int(Path("/proc/sys/vm/max_map_count").read_text().strip())
    except (OSError, ValueError):
        return None


WARM_CACHE_CODE = """
import protocols
from protocols.warm_up import exercise_codecs
status = protocols.Status(t_us=0, events_generated=0, events_sent=0, events_dropped=0,
                          events_queued=0, late_ticks=0, rx_errors=0, running=True)
for fd in (False, True):
    exercise_codecs(protocols.CanEncoder(board_id=0, fd=fd, step_us=100),
                    protocols.CanDecoder(board_id=0, fd=fd), 100, status)
"""


def warm_numba_cache(cwd: Path, timeout_s: float = 300.0) -> None:
    """Compile (or load) the board's numba kernels on this host, into numba's on-disk cache.

    UML sees the same files, so its programs then load the kernels instead of compiling
    them with slow system calls and hundreds of MB more memory: one short ``skinhil serve``
    over ``loop://`` (model, neurons, serial codec) and the CAN codecs, classic and FD.
    """
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(cwd)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])}
    for argv in ([sys.executable, "-m", "skinhil", "serve", "--port", "loop://",
                  "--duration", "0.01", "--quiet"],
                 [sys.executable, "-c", WARM_CACHE_CODE]):
        subprocess.run(argv, cwd=cwd, env=env, check=True, timeout=timeout_s,
                       stdin=subprocess.DEVNULL, capture_output=True)


def in_uml() -> bool:
    """True inside the UML machine started by :func:`run_in_uml`."""
    return os.environ.get(IN_UML_ENV) == "1"


def _find_module(kernel_dir: Path, name: str) -> Path:
    hits = sorted(p for p in kernel_dir.rglob(f"{name}.ko*")
                  if p.name == f"{name}.ko" or p.name.startswith(f"{name}.ko."))
    if not hits:
        raise UmlUnavailable(f"UML kernel module {name}.ko not found under {kernel_dir}; "
                             "install Debian's user-mode-linux package")
    return hits[0]


def _plain_module(path: Path, workdir: Path) -> Path:
    """``path`` itself if uncompressed, else a decompressed copy in ``workdir``."""
    suffix = path.name.split(".ko", 1)[1]
    if not suffix:
        return path
    out = workdir / path.name.split(".ko", 1)[0]
    out = out.with_name(out.name + ".ko")
    if suffix == ".xz":
        out.write_bytes(lzma.decompress(path.read_bytes()))
    elif suffix == ".gz":
        out.write_bytes(gzip.decompress(path.read_bytes()))
    elif suffix == ".zst":
        zstd = shutil.which("zstd")
        if zstd is None:
            raise UmlUnavailable(f"{path} is zstd-compressed and the zstd tool is missing")
        subprocess.run([zstd, "-q", "-d", "-f", str(path), "-o", str(out)], check=True)
    else:
        raise UmlUnavailable(f"unknown module compression {suffix!r} of {path}")
    return out


def uml_setup() -> tuple[str, Path]:
    """The UML kernel binary and its module directory; raises :class:`UmlUnavailable`."""
    kernel = shutil.which(UML_KERNEL)
    if kernel is None:
        raise UmlUnavailable("user-mode Linux kernel 'linux' not on PATH; "
                             "apt-get install -y user-mode-linux kmod iproute2")
    versions = sorted(p for p in UML_MODULES_ROOT.glob("*/kernel") if p.is_dir())
    if not versions:
        raise UmlUnavailable(f"no UML modules under {UML_MODULES_ROOT}; "
                             "apt-get install -y user-mode-linux")
    for tool in ("insmod", "ip"):
        if shutil.which(tool, path=os.environ.get("PATH", "") + ":/usr/sbin:/sbin") is None:
            raise UmlUnavailable(f"{tool!r} missing; apt-get install -y kmod iproute2")
    return kernel, versions[-1]


def _init_script(workdir: Path, modules: list[Path], command: list[str], cwd: Path,
                 env: dict[str, str]) -> str:
    q = shlex.quote
    lines = [
        "#!/bin/sh",
        f"date +%s.%N > {q(str(workdir / 'started'))}",
        "mount -t proc proc /proc",
        "mount -t sysfs sysfs /sys",
        # UML's devtmpfs has no /dev/shm: without it every multiprocessing lock (worker
        # pools, scikit-learn) fails with ENOENT
        "mkdir -p /dev/shm && mount -t tmpfs -o size=256m tmpfs /dev/shm",
        "export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin",
        f"exec 3> {q(str(workdir / 'setup.log'))}",
    ]
    for mod in modules:
        lines.append(f"insmod {q(str(mod))} 1>&3 2>&3 || echo 'insmod {mod.name} failed' >&3")
    lines += [
        "ip link add dev vcan0 type vcan 1>&3 2>&3",
        "ip link set up vcan0 1>&3 2>&3",
        # a second bus: a recording made on vcan0 is replayed onto vcan1
        "ip link add dev vcan1 type vcan 1>&3 2>&3",
        "ip link set up vcan1 1>&3 2>&3",
        "ip link set up lo 1>&3 2>&3",
        # the receive buffers the transports ask for (8 MB): UML's default cap, 208 KB,
        # overflowed a receiver stalled by the loaded host, and the board then got its
        # DECISIONs seconds late or after it had stopped (the answer loop's flaky failure)
        "echo 8388608 > /proc/sys/net/core/rmem_max 2>&3",
        "echo 8388608 > /proc/sys/net/core/wmem_max 2>&3",
    ]
    for key, value in env.items():
        lines.append(f"export {key}={q(value)}")
    lines += [
        f"cd {q(str(cwd))}",
        f"date +%s.%N > {q(str(workdir / 'command_start'))}",
        f"{shlex.join(command)} > {q(str(workdir / 'output'))} 2>&1 < /dev/null",
        f"echo $? > {q(str(workdir / 'returncode'))}.tmp",
        f"date +%s.%N > {q(str(workdir / 'command_end'))}",
        f"mv {q(str(workdir / 'returncode'))}.tmp {q(str(workdir / 'returncode'))}",
        "sync",
        "echo o > /proc/sysrq-trigger",
        "halt -f",
        "sleep 5",
    ]
    return "\n".join(lines) + "\n"


def _read_float(path: Path) -> float | None:
    try:
        return float(path.read_text().strip())
    except (OSError, ValueError):
        return None


def run_in_uml(command: list[str], cwd: Path, timeout_s: float = 300.0,
               mem: str = "2G", extra_env: dict[str, str] | None = None) -> UmlResult:
    """Boot UML, set up vcan0, run ``command`` in ``cwd`` and return its outcome.

    ``PATH`` starts with the directory of this Python (so ``python`` is the same
    interpreter), ``PYTHONPATH`` holds ``cwd`` and the variables in :data:`PASSED_ENV` are
    copied. Raises :class:`UmlUnavailable` when UML cannot be used, ``TimeoutError`` after
    ``timeout_s`` (s) of wall time (the UML processes are killed).
    """
    kernel, moddir = uml_setup()
    cwd = Path(cwd).resolve()
    with tempfile.TemporaryDirectory(prefix="skinhil-uml-") as tmp:
        workdir = Path(tmp)
        modules = [_plain_module(_find_module(moddir, name), workdir) for name in CAN_MODULES]
        env = {k: os.environ[k] for k in PASSED_ENV if k in os.environ}
        pydir = str(Path(sys.executable).parent)
        env["PATH"] = f"{pydir}:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
        env["PYTHONPATH"] = os.pathsep.join(
            [str(cwd)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
        env["HOME"] = env.get("HOME", "/root")
        env["TMPDIR"] = "/tmp"
        env[IN_UML_ENV] = "1"
        env.update(extra_env or {})
        script = workdir / "init.sh"
        script.write_text(_init_script(workdir, modules, command, cwd, env))
        script.chmod(0o755)
        argv = [kernel, f"mem={mem}", "rootfstype=hostfs", "rw", f"init={script}",
                "con=null", "con0=fd:0,fd:1", "quiet"]
        t0 = time.time()
        console_path = workdir / "console"
        with open(console_path, "wb") as console:
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=console,
                                    stderr=subprocess.STDOUT, start_new_session=True,
                                    env={**os.environ, "TMPDIR": tempfile.gettempdir()})
            try:
                proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                _kill_group(proc)
                raise TimeoutError(
                    f"user-mode Linux did not finish within {timeout_s:g} s; console:\n"
                    + console_path.read_text(errors="replace")[-4000:]
                    + _tail(workdir / "output")) from None
            finally:
                if proc.poll() is None:
                    _kill_group(proc)
        total = time.time() - t0
        started = _read_float(workdir / "started")
        c0 = _read_float(workdir / "command_start")
        c1 = _read_float(workdir / "command_end")
        rc_text = (workdir / "returncode").read_text().strip() \
            if (workdir / "returncode").exists() else ""
        setup_log = (workdir / "setup.log").read_text(errors="replace") \
            if (workdir / "setup.log").exists() else ""
        return UmlResult(
            returncode=int(rc_text) if rc_text.lstrip("-").isdigit() else None,
            output=(workdir / "output").read_text(errors="replace")
            if (workdir / "output").exists() else "",
            boot_s=None if started is None else started - t0,
            command_s=None if c0 is None or c1 is None else c1 - c0,
            total_s=total,
            console=console_path.read_text(errors="replace") + setup_log,
        )


def _tail(path: Path, n: int = 4000) -> str:
    try:
        return "\noutput:\n" + path.read_text(errors="replace")[-n:]
    except OSError:
        return ""


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--cwd", type=Path, default=Path(__file__).resolve().parents[1],
                        help="directory to run the command in (default: the repository)")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds (default 600)")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- command and arguments")
    args = parser.parse_args(argv)
    cmd = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not cmd:
        parser.error("give a command after --")
    try:
        res = run_in_uml(cmd, args.cwd, timeout_s=args.timeout)
    except UmlUnavailable as exc:
        print(f"uml_vcan: {exc}", file=sys.stderr)
        return 3
    sys.stdout.write(res.output)
    print(f"[uml_vcan: {platform.node()} boot {res.boot_s or float('nan'):.2f} s, command "
          f"{res.command_s or float('nan'):.2f} s, total {res.total_s:.2f} s, "
          f"exit {res.returncode}]", file=sys.stderr)
    return 1 if res.returncode is None else res.returncode


if __name__ == "__main__":
    sys.exit(main())
