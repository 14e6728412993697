"""The suites shipped in the package, by id (``name-vVERSION``), and ``SUITE:CASE`` refs."""

from __future__ import annotations

from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, MeshSize
from skinhil.suites import tactile_v1
from skinhil.suites.case import Case, Suite, Trials

SUITES: dict[str, Suite] = {s.id: s for s in (tactile_v1.SUITE,)}
"""Every suite by its id."""


def suite(suite_id: str) -> Suite:
    """The suite ``suite_id`` (e.g. ``tactile-v1``); refused with the ids there are."""
    try:
        return SUITES[suite_id]
    except KeyError:
        raise ConfigError(f"no suite {suite_id!r}: give one of {', '.join(SUITES)} "
                          "(skinhil suites lists them)") from None


def case_ref(ref: str) -> tuple[Suite, Case]:
    """The suite and case of ``SUITE:CASE`` (e.g. ``tactile-v1:grasp``)."""
    name, sep, case = ref.partition(":")
    if not sep or not case:
        raise ConfigError(f"--suite {ref!r}: give SUITE:CASE, e.g. tactile-v1:grasp")
    s = suite(name)
    return s, s.case(case)


def suite_trials(ref: str, seed: int, size: MeshSize = PAPER_SIZE) -> Trials:
    """The trials the case ``SUITE:CASE`` draws for ``seed`` on a skin of top-layer
    ``size``: what ``serve --suite`` plays."""
    s, case = case_ref(ref)
    return case.generate(s.id, seed, size)
