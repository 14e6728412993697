"""The seeds a dataset is made of: ``1-200``, ``1,2,5-9``, refused outside the suite's training
range (docs/suites.md "Seeds": an evaluation seed's trials are never trained on)."""

from __future__ import annotations

from skinhil.errors import ConfigError
from skinhil.suites import Suite

MAX_SEEDS = 100_000
"""Most seeds one dataset takes (a guard against a typo such as ``1-999999``)."""


def parse_seeds(text: str) -> list[int]:
    """The seeds of ``text``: comma-separated whole numbers and inclusive ranges ``A-B``, in
    the order given, each once."""
    seeds: list[int] = []
    for part in (p.strip() for p in text.split(",")):
        lo, sep, hi = part.partition("-")
        try:
            a = int(lo)
            b = int(hi) if sep else a
        except ValueError:
            raise ConfigError(f"--seeds {text!r}: give whole numbers and ranges, e.g. 1-200 "
                              "or 1,2,5-9") from None
        if a < 0 or b < a:
            raise ConfigError(f"--seeds {text!r}: a range A-B needs 0 <= A <= B, e.g. 1-200")
        if len(seeds) + b - a + 1 > MAX_SEEDS:
            raise ConfigError(f"--seeds {text!r}: at most {MAX_SEEDS} seeds in one dataset")
        seeds.extend(range(a, b + 1))
    return list(dict.fromkeys(seeds))


def check_training(suite: Suite, seeds: list[int]) -> None:
    """Refuse any seed of ``seeds`` outside ``suite``'s training range, with one line saying
    why: a decoder trained on an evaluation seed's trials would be scored on what it saw."""
    train = suite.training_seeds
    for seed in seeds:
        if seed not in train:
            raise ConfigError(
                f"seed {seed} is not a training seed of {suite.id}: training uses seeds "
                f"{train.start}-{train.stop - 1} only, evaluation (bench --suite) draws from "
                f"{suite.evaluation_seeds.start} on, so a decoder never sees the trials it is "
                "scored on; give seeds in the training range")
