"""What the demo prepares on first use: where it caches what it fits (its decoder, the grip
readout), and the board's kernels warmed meanwhile in another process. The cached decoder is
what every command that decodes takes when given no ``--model`` (:func:`demo_decoder`)."""

from __future__ import annotations

import contextlib
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

from protocols.kernel_cache import source_hash
from skinhil import child_processes
from skinhil.cli.direction_names import class_names
from skinhil.cli.options import DECODE_SNR_DB
from skinhil.cli.train import print_report
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize, format_size
from skinhil.model.timeline import DEFAULT_REST_S
from skinhil.receiver.session import serve_command
from skinhil.receiver.training import train_decoder
from skinhil.transports import PtyMasterTransport

DEMO_REST_S = DEFAULT_REST_S
"""Rest (s) after each stimulus: the board's default."""
DEMO_REPS = 30
"""Training stimuli per condition for the cached demo model. At 10 dB the decoder is
data-limited below this: cross-validated window accuracy 83 % with 15 per condition, 97 %
with 30 (``skinhil train --reps``, seed 0)."""
MODEL_FORMAT_TAG = "v3"
"""Bumped when the cached model's file format changes; the file name also carries the hash
of the package sources (:func:`protocols.kernel_cache.source_hash`), so a model is retrained
once after any change of the code that simulated, cut and fitted its windows."""

DEMO_BOARD_SEED = 1
"""Seed of the one-tick board that warms the kernels while the demo decoder trains."""


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/skinhil`` or ``~/.cache/skinhil``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "skinhil"


@contextlib.contextmanager
def board_warming(baud: int, snr_db: float, seed: int) -> Iterator[None]:
    """While the body runs, a one-tick board (the demo's command line) on a throwaway pty
    compiles or loads the board's kernels in another process, on the other core: from a
    fresh clone that is ~15 s the demo's board then does not spend before its first tick."""
    link, slave_fd = PtyMasterTransport.open_pair(baud)
    board = child_processes.start(
        serve_command(["--port", link.slave_path, "--baud", str(baud)], 0.001, snr_db, seed,
                      DEFAULT_REST_S), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    try:
        yield
        board.wait(timeout=600)
    finally:
        if board.poll() is None:
            board.kill()
            board.wait()
        link.shutdown()
        os.close(slave_fd)


def demo_decoder(size: MeshSize | None, quiet: bool, baud: int) -> Path:
    """The decoder a command given no ``--model`` decodes with: the cached demo decoder at
    the paper's 10 dB (:func:`cached_model`), for a skin of top-layer ``size`` (None: the
    paper's 6x6, the only size it fits; another is refused, saying to give --model)."""
    if size is not None and tuple(size) != tuple(PAPER_SIZE):
        raise ConfigError(f"the demo's decoder fits the 6x6 skin, not {format_size(size)} — "
                          "give --model FILE (skinhil train --size ...)")
    return cached_model(DECODE_SNR_DB, quiet, baud, DEMO_BOARD_SEED)


def cached_model(snr_db: float, quiet: bool, baud: int, seed: int) -> Path:
    """The cached demo model for ``snr_db``, trained now (with a progress bar) if missing,
    while the board's kernels warm up for a board at ``baud`` and ``seed``."""
    stem = f"demo-decoder-{snr_db:g}dB-rest{DEMO_REST_S:g}s-{MODEL_FORMAT_TAG}"
    path = cache_dir() / f"{stem}-{source_hash()}.npz"
    if path.exists():
        return path
    try:  # before the training, not after it
        path.parent.mkdir(parents=True, exist_ok=True)
        if not os.access(path.parent, os.W_OK):
            raise PermissionError(13, "Permission denied")
    except OSError as exc:
        raise ConfigError(f"the demo's model cache '{path.parent}' cannot be written "
                          f"({exc.strerror or exc}) — set XDG_CACHE_HOME to a writable folder "
                          "or give --model FILE") from None
    print(f"training the demo model at {snr_db:g} dB (first use; cached in {path.parent})",
          flush=True)
    with board_warming(baud, snr_db, seed):
        decoder, report = train_decoder(snr_db, DEMO_REPS, seed=0, rest_s=DEMO_REST_S,
                                        progress=not quiet)
    if not quiet:
        print_report(report, class_names())
    path.parent.mkdir(parents=True, exist_ok=True)
    decoder.save(path)
    for old in path.parent.glob(f"{stem}*.npz"):  # models of earlier sources
        if old != path:
            old.unlink(missing_ok=True)
    return path
