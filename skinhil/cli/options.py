"""Model options shared by the subcommands that build a skin (simulate, serve, train, ...)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from skinhil.cli.values import integer, real, seed_value, size_value, snr_value
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.model.mechanics.readout import READOUTS
from skinhil.model.neurons import NoiseParams
from skinhil.model.schedule_file import MAX_FILE_BYTES, load_schedule
from skinhil.model.skin import (
    AMPLITUDES,
    AUTO_GEOMETRIC_MAX_SPRINGS,
    DEFAULT_AMPLITUDE,
    SkinModel,
    SkinParams,
)
from skinhil.model.stimuli import Schedule
from skinhil.world.scenario_file import Scenario, load_scenario

DT_RANGE_S = (1e-6, 1e-2)
"""Simulation steps (s) the options take: from 1 µs to 10 ms (the geometric mechanics and the
board, whose 1 ms tick is a whole number of steps, refuse the larger ones themselves)."""
MAX_THREADS = 256
"""Most model threads."""
DECODE_SNR_DB = 10.0
"""Default noise level (dB) of ``skinhil train`` and ``skinhil demo``: the paper's operating
point (Figure 4)."""


SNR_HELP = "neuron noise SNR in dB, -20..200 or 'inf' for none (default: %(default)g)"
"""``--snr-db``'s help, the same on every command."""
SEED_HELP = "noise and schedule seed, 0..2^63-1 (default: %(default)s)"
"""``--seed``'s help, the same on every command whose seed draws the noise and schedule."""


def add_snr_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup,
                   default: float = DECODE_SNR_DB) -> None:
    """Add --snr-db (neuron noise, dB; ``default`` 10, the paper's operating point)."""
    parser.add_argument("--snr-db", type=snr_value, default=default, metavar="DB",
                        help=SNR_HELP)


def add_seed_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup,
                    default: int = 0) -> None:
    """Add --seed (the noise and schedule seed; ``default`` 0)."""
    parser.add_argument("--seed", type=seed_value, default=default, help=SEED_HELP)


def add_size_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add --size ROWSxCOLS (the skin's top layer; default the paper's 6x6) to ``parser``."""
    parser.add_argument("--size", type=size_value, default=PAPER_SIZE, metavar="ROWSxCOLS",
                        help="top layer of the skin in masses, e.g. 16x16; the layers below "
                             "follow the pyramid rule; built-in stimuli keep their place "
                             "relative to the centre (default: 6x6, the paper's 338 sensors)")


def add_model_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup,
                      snr_default: float = DECODE_SNR_DB) -> None:
    """Add --size, --mechanics, --readout, --amplitude, --dt, --snr-db, --noise, --seed,
    --threads to ``parser``."""
    add_size_option(parser)
    parser.add_argument("--mechanics", choices=("auto", "linear", "geometric"), default="auto",
                        help="skin mechanics: 'geometric' (true spring lengths; reproduces "
                             "the paper), 'linear' (small-displacement stiffness matrix; "
                             "cheaper) or 'auto', geometric up to "
                             f"{AUTO_GEOMETRIC_MAX_SPRINGS} springs (10x10) and linear above, "
                             "where geometric would not keep real time (default: auto)")
    parser.add_argument("--readout", choices=READOUTS, default="length",
                        help="what each spring reports: 'length', k x its length change "
                             "(default), or 'axial', the small-displacement projection "
                             "k e.(q_j - q_i)")
    parser.add_argument("--amplitude", choices=tuple(AMPLITUDES), default=DEFAULT_AMPLITUDE,
                        help="the skin's regime: 'small' (default: M 10 g, K 5000 N/m, C 5 "
                             "N.s/m per mass and spring, a 0.5 N touch at ~3 %% strain) or "
                             "'paper' (M, K and C x0.01, the paper's regime: the same modes "
                             "and linear forces at 100x the displacement, 150-400 %% strain)")
    parser.add_argument("--dt", dest="dt_s", type=real(*DT_RANGE_S, "seconds"), default=1e-4,
                        metavar="SECONDS",
                        help=f"simulation step in seconds, {DT_RANGE_S[0]:g}..{DT_RANGE_S[1]:g}"
                             " (default: 1e-4)")
    add_snr_option(parser, snr_default)
    parser.add_argument("--noise", choices=("diffusion", "measured"), default="diffusion",
                        help="how the SNR becomes neuron noise: 'diffusion', sigma^2 = 1 mV^2 x "
                             "10^(-SNR/10) per ms whatever the step (default), or 'measured', "
                             "awgn(x, snr, 'measured') every step (runs away below ~24 dB)")
    add_seed_option(parser)
    parser.add_argument("--threads", type=integer(1, MAX_THREADS, "thread count"), default=1,
                        metavar="N",
                        help="threads for the model (diffusion noise), worth it from a few "
                             "thousand channels: offline the neurons share them (the same "
                             "spikes as one thread); serve steps the mechanics on one and the "
                             "neurons on the others, two ticks behind (default: 1)")


def noise_from_args(args: argparse.Namespace) -> NoiseParams:
    """The neuron noise definition selected by :func:`add_model_options`' ``--noise``."""
    return NoiseParams(definition=args.noise)


def model_from_args(args: argparse.Namespace) -> SkinModel:
    """The skin model selected by :func:`add_model_options`' options."""
    return SkinModel(SkinParams.at_amplitude(args.amplitude, mechanics=args.mechanics,
                                             readout=args.readout, size=args.size))


SCHEDULE_HELP = ("schedule or scenario file (TOML: stimuli and contacts; format and limits: "
                 "docs: Schedule files, docs: Contact)")
"""The help text of every option that takes a schedule file."""
SCHEDULE_NOTICE_BYTES = 1 << 20
"""Schedule files from this size (1 MiB, ~0.3 s to read) on are announced before reading."""


def read_scenario(path: Path, size: MeshSize) -> Scenario:
    """The scenario (schedule file with contact tables, or a plain schedule) ``path`` for a
    skin of top-layer ``size``; a big file is announced first, as by
    :func:`read_schedule`."""
    _announce(path)
    return load_scenario(path, size)


def _announce(path: Path) -> None:
    try:
        n_bytes = path.stat().st_size
    except OSError:
        n_bytes = 0  # the loader says what is wrong with the path
    if SCHEDULE_NOTICE_BYTES <= n_bytes <= MAX_FILE_BYTES:  # larger ones are refused at once
        print(f"skinhil: reading schedule {path} ({n_bytes / 2**20:.1f} MiB, about "
              f"{n_bytes / 2**20 * 0.3:.0f} s)", file=sys.stderr, flush=True)


def read_schedule(path: Path, size: MeshSize) -> Schedule:
    """The schedule file ``path`` for a skin of top-layer ``size``, checked against its
    schema; a big file is announced on stderr first (its reading takes a while)."""
    _announce(path)
    return load_schedule(path, size)
