"""``skinhil dataset``'s work: the samples of a suite's cases over training seeds, labelled,
written to one SHD-layout file (:mod:`skinhil.dataset.shd_file`)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from firmware_sim.config import DEFAULT_RESPONSE_WINDOW_S
from skinhil import __version__
from skinhil.dataset.samples import Sample, case_samples, skin_model
from skinhil.dataset.seeds import check_training
from skinhil.dataset.shd_file import write_samples
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.suites import Case, Suite

log = logging.getLogger(__name__)

SAMPLE_TEXT = ("one trial of a case: its spikes from the trial's onset (a slip's: its "
               "contact's touch-down) to the end of its answer window (the trial's onset + "
               "response_window_s)")
"""The root's ``sample`` attribute."""


@dataclass(frozen=True)
class Written:
    """What :func:`make_dataset` wrote: the file, its sample count and spike count."""

    path: Path
    samples: int
    spikes: int


def dataset_cases(suite: Suite, names: Sequence[str] | None) -> list[Case]:
    """The cases ``names`` of ``suite`` (default: every case that poses one answered task);
    a case with a held object, whose lifts depend on the decoder's grip, is refused."""
    if names is None:
        return [c for c in suite.cases if not c.held_object and len(c.tasks) == 1]
    cases = [suite.case(n) for n in names]
    for c in cases:
        if c.held_object or len(c.tasks) != 1:
            raise ConfigError(f"case {c.name!r} of {suite.id} poses no one answered task (its "
                              "score is the grip's closed loop): it has no offline samples; "
                              "leave it out of --cases")
    return cases


def class_keys(cases: Sequence[Case]) -> list[str]:
    """The class names of ``cases``' class tasks, ``task:value`` (a classification's value is
    the stimulus id, a vibration's the frequency in Hz), in case order: ``labels`` index
    them."""
    return [f"{t.name}:{v:g}" for c in cases for t in c.tasks for v in t.classes]


def label(keys: Sequence[str], sample: Sample) -> int:
    """The index of ``sample``'s class in ``keys`` (-1: its task has no classes)."""
    if sample.class_value is None:
        return -1
    return keys.index(f"{sample.task}:{sample.class_value:g}")


def make_dataset(out: Path, suite: Suite, seeds: Sequence[int],
                 cases: Sequence[Case], snr_db: float, size: MeshSize = PAPER_SIZE,
                 dt_s: float = 1e-4, response_window_s: float = DEFAULT_RESPONSE_WINDOW_S,
                 progress: Callable[[str, int], None] | None = None) -> Written:
    """Simulate ``cases`` of ``suite`` for each of ``seeds`` (training seeds only) offline at
    ``snr_db`` (dB) and write their samples to ``out``; ``progress(case, seed)`` is called as
    each run is done."""
    check_training(suite, list(seeds))
    samples: list[Sample] = []
    for seed in seeds:
        for case in cases:
            trials = case.generate(suite.id, seed, size)
            samples += case_samples(trials, snr_db, dt_s, size, response_window_s)
            if progress is not None:
                progress(case.name, seed)
    keys = class_keys(cases)
    attrs = {"suite": suite.id, "suite_name": suite.name, "suite_version": suite.version,
             "skinhil_version": __version__, "seeds": list(seeds),
             "cases": [c.name for c in cases], "snr_db": snr_db, "dt_s": dt_s,
             "size": list(size), "response_window_s": response_window_s,
             "sample": SAMPLE_TEXT}
    write_samples(out, samples, keys, [label(keys, s) for s in samples],
                  skin_model(size).mesh, attrs)
    log.info("wrote %d samples to %s", len(samples), out)
    return Written(out, len(samples), sum(len(s.t_us) for s in samples))
