"""Model options shared by the subcommands that build a skin (simulate, serve, train, ...)."""

from __future__ import annotations

import argparse
import math

from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize, parse_size
from skinhil.model.mechanics.readout import READOUTS
from skinhil.model.neurons import NoiseParams
from skinhil.model.skin import AUTO_GEOMETRIC_MAX_SPRINGS, SkinModel, SkinParams

DECODE_SNR_DB = 10.0
"""Default noise level (dB) of ``skinhil train`` and ``skinhil demo``: the paper's operating
point (Figure 4)."""


def snr_value(text: str) -> float:
    """argparse type: an SNR in dB, or 'inf' for no noise."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of dB (or 'inf')") from None
    if math.isnan(value) or value == -math.inf:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of dB (or 'inf')")
    return value


def size_value(text: str) -> MeshSize:
    """argparse type: a mesh size ROWSxCOLS (>= 3x3)."""
    try:
        return parse_size(text)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_size_option(parser: argparse.ArgumentParser) -> None:
    """Add --size ROWSxCOLS (the skin's top layer; default the paper's 6x6) to ``parser``."""
    parser.add_argument("--size", type=size_value, default=PAPER_SIZE, metavar="ROWSxCOLS",
                        help="top layer of the skin in masses, e.g. 16x16; the layers below "
                             "follow the pyramid rule; built-in stimuli keep their place "
                             "relative to the centre (default: 6x6, the paper's 338 sensors)")


def add_model_options(parser: argparse.ArgumentParser, snr_default: float = math.inf) -> None:
    """Add --size, --mechanics, --readout, --dt, --snr-db, --noise, --seed, --threads to
    ``parser``."""
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
    parser.add_argument("--dt", dest="dt_s", type=float, default=1e-4, metavar="SECONDS",
                        help="simulation step in seconds (default: 1e-4)")
    parser.add_argument("--snr-db", type=snr_value, default=snr_default, metavar="DB",
                        help=f"neuron noise SNR in dB, 'inf' for none (default: {snr_default:g})")
    parser.add_argument("--noise", choices=("diffusion", "measured"), default="diffusion",
                        help="how the SNR becomes neuron noise: 'diffusion', sigma^2 = 1 mV^2 x "
                             "10^(-SNR/10) per ms whatever the step (default), or 'measured', "
                             "awgn(x, snr, 'measured') every step (runs away below ~24 dB)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed (default: 0)")
    parser.add_argument("--threads", type=int, default=1, metavar="N",
                        help="threads for the model (diffusion noise), worth it from a few "
                             "thousand channels: offline the neurons share them (the same "
                             "spikes as one thread); serve steps the mechanics on one and the "
                             "neurons on the others, two ticks behind (default: 1)")


def noise_from_args(args: argparse.Namespace) -> NoiseParams:
    """The neuron noise definition selected by :func:`add_model_options`' ``--noise``."""
    return NoiseParams(definition=args.noise)


def model_from_args(args: argparse.Namespace) -> SkinModel:
    """The skin model selected by :func:`add_model_options`' options."""
    if not (math.isfinite(args.dt_s) and args.dt_s > 0):
        raise ConfigError(f"--dt must be a positive number of seconds, got {args.dt_s!r}")
    return SkinModel(SkinParams(mechanics=args.mechanics, readout=args.readout,
                                size=args.size))
