"""Model options shared by the subcommands that build a skin (simulate, serve, train, ...)."""

from __future__ import annotations

import argparse
import math

from skinhil.errors import ConfigError
from skinhil.skin import SkinModel, SkinParams

DECODE_SNR_DB = 40.0
"""Default noise level (dB) of ``skinhil train`` and ``skinhil demo``: noisy, yet the force,
not the noise, drives the spikes. Below ~24 dB the measured-power noise of the model runs
away (``skinhil/neurons.py``) and at 10 dB no stimulus onset can be detected, so no decoder
can be trained there (see docs/receiver.md)."""


def snr_value(text: str) -> float:
    """argparse type: an SNR in dB, or 'inf' for no noise."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of dB (or 'inf')") from None
    if math.isnan(value) or value == -math.inf:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of dB (or 'inf')")
    return value


def add_model_options(parser: argparse.ArgumentParser, snr_default: float = math.inf) -> None:
    """Add --mechanics, --dt, --snr-db, --seed to ``parser``."""
    parser.add_argument("--mechanics", choices=("linear", "geometric"), default="linear",
                        help="skin mechanics (default: linear)")
    parser.add_argument("--dt", dest="dt_s", type=float, default=1e-4, metavar="SECONDS",
                        help="simulation step in seconds (default: 1e-4)")
    parser.add_argument("--snr-db", type=snr_value, default=snr_default, metavar="DB",
                        help=f"neuron noise SNR in dB, 'inf' for none (default: {snr_default:g})")
    parser.add_argument("--seed", type=int, default=0, help="noise seed (default: 0)")


def model_from_args(args: argparse.Namespace) -> SkinModel:
    """The skin model selected by :func:`add_model_options`' options."""
    if not (math.isfinite(args.dt_s) and args.dt_s > 0):
        raise ConfigError(f"--dt must be a positive number of seconds, got {args.dt_s!r}")
    return SkinModel(SkinParams(mechanics=args.mechanics))
