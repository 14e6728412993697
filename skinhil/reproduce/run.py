"""``reproduce``: compute everything for both mechanics with both readouts at both amplitudes
(the 2 x 2 x 2 design that names the cause of each claim's outcome), write the figures and
REPORT.md."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path

from skinhil.errors import ConfigError
from skinhil.model.mechanics.readout import READOUTS
from skinhil.reproduce.compute import (
    MechanicsResults,
    Regime,
    ReproduceConfig,
    compute_mechanics,
    compute_regime,
    compute_supplementary,
)
from skinhil.reproduce.figures import _pyplot, write_figures
from skinhil.reproduce.paper_search import SEARCH_FILE, SearchSpace, load_or_run
from skinhil.reproduce.report import write_report

logger = logging.getLogger(__name__)

MECHANICS = ("linear", "geometric")


@dataclass(frozen=True)
class ReproduceOutcome:
    """Where the report and figures went, the results, and the wall time (s)."""

    report: Path
    figures: list[Path]
    results: list[MechanicsResults]
    regime: Regime | None
    seconds: float


def reproduce(out: str | Path, config: ReproduceConfig | None = None,
              quick: bool = False, search_only: bool = False) -> ReproduceOutcome:
    """Run the whole reproduction into directory ``out`` (created if missing). The ``paper``
    preset's search (:mod:`skinhil.reproduce.paper_search`) is read from ``out`` if cached
    there, else run first; ``search_only`` runs (and caches) that stage alone."""
    cfg = config or (ReproduceConfig.quick() if quick else ReproduceConfig())
    if not search_only:
        _pyplot()  # fail early, before minutes of work, if matplotlib is missing
    path = Path(out)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot create output directory {str(path)!r}: "
                          f"{exc.strerror or exc}") from None
    start = time.perf_counter()
    space = SearchSpace.quick() if quick else SearchSpace()
    search = load_or_run(path, space, force=search_only)
    if search_only:
        return ReproduceOutcome(path / SEARCH_FILE, [], [], None,
                                time.perf_counter() - start)
    results = [compute_mechanics(m, r, cfg, a)  # type: ignore[arg-type]
               for a in cfg.amplitudes for m in MECHANICS for r in READOUTS]
    regime = compute_regime(cfg.dt_s)
    figures = write_figures(results, path, cfg.dt_s, compute_supplementary(cfg.dt_s))
    total = time.perf_counter() - start
    report = write_report(results, regime, cfg, path, total, quick, search)
    logger.info("reproduction written to %s in %.1f s", path, total)
    return ReproduceOutcome(report, figures, results, regime, total)
