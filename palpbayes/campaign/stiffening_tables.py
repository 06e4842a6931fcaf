"""The stiffening law of each material × tip, as the tables the report draws.

:func:`fit_stiffening_tables` fits the law E(rest time) (:func:`palpbayes.stiffening.
fit_stiffening_summary`) to the Bayesian rows of every group whose palpations span
:data:`STIFFENING_MIN_REST_TIMES` or more distinct positive rest times, and returns three
tables that ``palpbayes compare`` writes (file names: :mod:`palpbayes.outputs`):

* ``stiffening.csv`` — one row per group: verdict, BICs, the preferred law's medians
  (:meth:`~palpbayes.stiffening.StiffeningResult.row`);
* ``stiffening_parameters.csv`` — the preferred law's parameters with their 90 % intervals
  (``material, tip, law, parameter, unit, median, sd, lo, hi``);
* ``stiffening_curves.csv`` — the preferred law's median and 90 % band of E(t) [Pa] on
  :data:`CURVE_POINTS` rest times from 0 to 1.05 × the longest (``material, tip, t_s,
  median_pa, lo_pa, hi_pa``).

The report reads them and fits nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..intervals import LEVEL
from .fitjob import trace_seed

__all__ = ["STIFFENING_MIN_REST_TIMES", "CURVE_POINTS", "StiffeningTables",
           "fit_stiffening_tables", "stiffening_rest_times"]

#: A material × tip gets a stiffening fit when its Bayesian rows span this many rest times.
STIFFENING_MIN_REST_TIMES = 3
#: Rest times of the stored curve of each group's law.
CURVE_POINTS = 300


@dataclass(frozen=True)
class StiffeningTables:
    """The three tables of the module docstring (each None when no group has a law)."""

    rows: pd.DataFrame | None
    parameters: pd.DataFrame | None
    curves: pd.DataFrame | None


def stiffening_rest_times(group: pd.DataFrame) -> pd.Series:
    """The positive rest times [s] of a group's rows whose statistical E is finite."""
    t = pd.to_numeric(group["rest_time_s"], errors="coerce")
    e = pd.to_numeric(group["E_stat_pa"], errors="coerce")
    return t[np.isfinite(t) & (t > 0) & np.isfinite(e)]


def fit_stiffening_tables(summary: pd.DataFrame, materials: list[str], tips: list[str],
                      seed: int, level: float = LEVEL) -> StiffeningTables:
    """Fit the stiffening law of every group with enough rest times (module docstring).

    Parameters
    ----------
    summary
        ``summary.csv`` (one row per trace × method, ``rest_time_s`` [s], ``E_stat_pa`` [Pa]).
    materials, tips
        The groups, in the order of the tables.
    seed
        The campaign's seed; each group's sampler seed is derived from it and its labels.
    level
        Probability content of the intervals and the band (0.9).
    """
    from ..stiffening import fit_stiffening_summary

    if "rest_time_s" not in summary or "E_stat_pa" not in summary:
        return StiffeningTables(None, None, None)
    rows, params, curves = [], [], []
    for mat in materials:
        for tip in tips:
            g = summary[(summary["material"] == mat) & (summary["tip"] == tip)
                        & (summary["method"] == "bayes")]
            t = stiffening_rest_times(g)
            if t.nunique() < STIFFENING_MIN_REST_TIMES:
                continue
            fit = fit_stiffening_summary(g, method="bayes",
                                         seed=trace_seed(seed, f"stiffening/{mat}/{tip}"))
            key = {"material": mat, "tip": tip}
            rows.append({**key, "method": "bayes", **fit.row()})
            tab = fit.table_of()
            params.append(tab.assign(**key, law=fit.law)[
                ["material", "tip", "law", *tab.columns]])
            grid = np.linspace(0.0, 1.05 * float(t.max()), CURVE_POINTS)
            curves.append(fit.predict(grid, level=level).assign(**key)[
                ["material", "tip", "t_s", "median_pa", "lo_pa", "hi_pa"]])
    if not rows:
        return StiffeningTables(None, None, None)
    return StiffeningTables(pd.DataFrame(rows), pd.concat(params, ignore_index=True),
                            pd.concat(curves, ignore_index=True))
