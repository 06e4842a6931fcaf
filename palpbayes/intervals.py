"""Central credible intervals: the one probability level and the one quantile helper.

Every reported interval of palpbayes (per-trace posteriors, pooled summaries, stiffening fits,
least-squares intervals, plots) is the central :data:`LEVEL` interval, cut at the quantiles
(1 - level)/2 and (1 + level)/2 of the draws.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LEVEL", "Z_LEVEL", "normal_z", "central", "central_band", "hull"]

#: Probability content of the reported central intervals.
LEVEL = 0.9


def normal_z(level: float = LEVEL) -> float:
    """z with P(|N(0, 1)| <= z) = ``level`` (1.645 at 90 %): the half-width in sd of a
    normal central interval."""
    from scipy.stats import norm

    return float(norm.ppf(0.5 + level / 2.0))


#: :func:`normal_z` of :data:`LEVEL`.
Z_LEVEL = normal_z()


def central(x, level: float = LEVEL) -> tuple[float, float]:
    """Central ``level`` interval (quantiles (1 − level)/2 and (1 + level)/2) of draws ``x``."""
    a = (1.0 - level) / 2.0
    lo, hi = np.quantile(np.asarray(x, dtype=float), [a, 1.0 - a])
    return float(lo), float(hi)


def central_band(x, level: float = LEVEL, axis: int = 0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower bound, median and upper bound of the central ``level`` band of draws ``x`` along
    ``axis`` (e.g. posterior curves, one draw per row)."""
    a = (1.0 - level) / 2.0
    lo, med, hi = np.quantile(np.asarray(x, dtype=float), [a, 0.5, 1.0 - a], axis=axis)
    return lo, med, hi


def hull(*intervals: tuple[float, float]) -> tuple[float, float]:
    """The smallest interval holding every one of ``intervals`` (lo, hi): how a wider interval
    of E is made to hold a narrower one it must contain (the budget's holds the statistical
    one, the full one the budget's: :meth:`palpbayes.bayes.result.BayesResult.intervals`).

    >>> hull((1.0, 3.0), (0.5, 2.0))
    (0.5, 3.0)
    """
    return (float(min(lo for lo, _ in intervals)), float(max(hi for _, hi in intervals)))

