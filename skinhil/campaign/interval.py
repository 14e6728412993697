"""The report card's 95 % interval: Wilson's score interval of a proportion.

A task's score over a suite's seeds is a proportion: ``k`` trials and answers judged right
out of ``n`` charged (``tasks.<task>.score`` = right / (trials + extra answers), pooled over
the seeds); the grasp's, lifts held and not broken out of lifts. Wilson's interval keeps
within [0, 1] and stays honest at 0 and at ``n``, where the normal approximation collapses
to a point. It treats the ``n`` charged items as independent: trials of one seed share a
decoder's run, so read it as the interval of the trials played, not of every seed there is.
"""

from __future__ import annotations

import math

Z_95 = 1.959963984540054
"""The standard normal quantile of 0.975: a two-sided 95 % interval."""
METHOD = "wilson"
"""What the card says its interval is."""


def wilson_interval(k: int, n: int, z: float = Z_95) -> tuple[float, float] | None:
    """Wilson's score interval (lo, hi) of the proportion ``k`` / ``n`` at the normal
    quantile ``z`` (:data:`Z_95`: 95 %); None when ``n`` is 0 (nothing was charged)."""
    if n <= 0:
        return None
    if not 0 <= k <= n:
        raise ValueError(f"a proportion needs 0 <= k <= n, got k={k}, n={n}")
    p = k / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    lo = 0.0 if k == 0 else max(0.0, centre - half)  # exact ends: 0 and 1 are bounds
    hi = 1.0 if k == n else min(1.0, centre + half)
    return lo, hi
