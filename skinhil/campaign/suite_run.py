"""A suite played as a campaign: every case of a suite (``skinhil/suites``) at seeds drawn
at run time from its evaluation range, against the decoder under test and, on the bench's
own link, against the baselines at the same seeds (``skinhil bench --suite``).

The suite becomes a :class:`~skinhil.campaign.campaign_file.Campaign` in memory (a scenario
per case, ``serve --suite SUITE:CASE``, the drawn seeds as the ``seed`` parameter), and the
campaign's runner plays it: one way to run a case. The decoder's run goes into ``OUT``
(``summary.json``, ``junit.xml``, ``cases/``); each baseline's into ``OUT/baselines/NAME``.
The oracle answers each case from the truth an earlier run of it recorded (the decoder's,
else a baseline's: the world's mechanics do not depend on the noise).

The reference receiver's model and the grip controller's readout are copied into
``OUT/inputs`` before the first case and every case reads the copies: the shared cache they
come from (``skinhil.cli.demo_cache``) drops the files of other package sources, so a
process of another checkout could delete them under a long run (its listeners then exit 2,
the cases are the rig's errors and their scores n/a), and the run's folder keeps what its
answerers used.
"""

from __future__ import annotations

import dataclasses
import hashlib
import shutil
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.campaign.campaign_file import Campaign, Scenario
from skinhil.campaign.case_run import TRUTH_NAME, BenchLink
from skinhil.campaign.criteria import Criterion
from skinhil.campaign.rig import RigBounds
from skinhil.campaign.runner import run_campaign
from skinhil.errors import ConfigError
from skinhil.suites import Suite

BASELINES = ("reference", "random", "oracle")
"""The baselines played beside the decoder (``listen --answer --answer-with``; the grasp's
reference controller rides with ``reference``)."""
MAX_SEEDS = 1000
"""Most seeds per case one run draws."""


def draw_seeds(suite: Suite, seed: int, count: int) -> list[int]:
    """``count`` distinct seeds of ``suite``'s evaluation range, drawn by a numpy Generator
    seeded with ``seed`` (the card records it: the same ``seed`` draws the same seeds)."""
    if not 1 <= count <= MAX_SEEDS:
        raise ConfigError(f"--seeds {count}: give 1..{MAX_SEEDS} seeds per case")
    rng = np.random.default_rng([seed, *suite.id.encode()])
    ev = suite.evaluation_seeds
    out: list[int] = []
    while len(out) < count:
        s = int(rng.integers(ev.start, ev.stop))
        if s not in out:
            out.append(s)
    return out


def suite_campaign(suite: Suite, seeds: list[int], cases: tuple[str, ...] = (),
                   criteria: tuple[Criterion, ...] = (),
                   rig: RigBounds | None = None) -> Campaign:
    """``suite``'s cases (all, or those named in ``cases``) at ``seeds`` as a campaign."""
    chosen = [suite.case(name) for name in cases] if cases else list(suite.cases)
    scenarios = tuple(Scenario(c.name, suite=f"{suite.id}:{c.name}") for c in chosen)
    text = f"{suite.id} {','.join(c.name for c in chosen)} {seeds} {criteria}"
    return Campaign(suite.id, Path(suite.id), hashlib.sha256(text.encode()).hexdigest(),
                    scenarios, {"seed": tuple(seeds)}, 1, criteria,
                    rig if rig is not None else RigBounds())


@dataclass(frozen=True)
class SuiteRun:
    """A suite run's summaries: the decoder's and each baseline's (campaign summaries,
    :mod:`~skinhil.campaign.summary_file`)."""

    decoder: dict[str, Any]
    baselines: dict[str, dict[str, Any]]


def _add_truths(truths: dict[str, Path], summaries: list[dict[str, Any]]) -> None:
    """Add to ``truths`` (case id -> truth file) the first truth file each case has in
    ``summaries``."""
    for summary in summaries:
        for record in summary["cases"]:
            path = Path(record["folder"]) / TRUTH_NAME
            if record["id"] not in truths and path.is_file():
                truths[record["id"]] = path


def baseline_folder(out: Path, name: str) -> Path:
    """Where baseline ``name``'s run goes."""
    return out / "baselines" / name


INPUTS_NAME = "inputs"
"""The folder of ``OUT`` that holds the answerers' model and readout copies."""


def keep_inputs(link: BenchLink, folder: Path) -> BenchLink:
    """``link`` reading copies in ``folder`` of its model and grip readout files."""
    copies: dict[str, Path] = {}
    for name in ("model", "grip_readout"):
        path: Path | None = getattr(link, name)
        if path is None:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        target = folder / path.name
        if not target.exists():
            try:
                shutil.copyfile(path, target)
            except OSError as exc:
                raise ConfigError(f"'{path}' cannot be copied into '{folder}' "
                                  f"({exc.strerror or exc}): give a writable --out") from None
        copies[name] = target
    return dataclasses.replace(link, **copies)  # type: ignore[arg-type]


def run_suite(campaign: Campaign, out: Path, link: BenchLink, link_text: str,
              stop: threading.Event, baseline_link: BenchLink | None = None,
              on_case: Callable[[str, dict[str, Any] | None], None] | None = None
              ) -> SuiteRun:
    """Play ``campaign`` (:func:`suite_campaign`) on ``link``, then, with ``baseline_link``
    (the bench's own link and the reference receiver's model), each of :data:`BASELINES`
    at the same cases and seeds; ``on_case(who, record)`` after each case. The links read
copies of their files in ``OUT/inputs`` (module docstring)."""
    link = keep_inputs(link, out / INPUTS_NAME)
    if baseline_link is not None:
        baseline_link = keep_inputs(baseline_link, out / INPUTS_NAME)

    def hook(who: str) -> Callable[[dict[str, Any] | None], None] | None:
        return None if on_case is None else (lambda record: on_case(who, record))

    decoder = run_campaign(campaign, out, link, link_text, stop, False, hook("decoder"))
    baselines: dict[str, dict[str, Any]] = {}
    if baseline_link is None:
        return SuiteRun(decoder, baselines)
    truths: dict[str, Path] = {}
    for name in BASELINES:
        if stop.is_set():
            break
        _add_truths(truths, [decoder, *baselines.values()])
        bl = dataclasses.replace(baseline_link, answer_with=name, oracle_truths=truths,
                                 grip_readout=baseline_link.grip_readout
                                 if name == "reference" else None)
        baselines[name] = run_campaign(campaign, baseline_folder(out, name), bl,
                                       f"bench pty pair, {name} answerer", stop, False,
                                       hook(name))
    return SuiteRun(decoder, baselines)
