"""The outcome of a stiffening fit (:class:`StiffeningResult`): verdict, tables, draws, curve.

Built by :func:`palpbayes.stiffening.fit.fit_stiffening`; one row of ``stiffening.csv`` is
:meth:`StiffeningResult.row`, the posterior band of E(t) :meth:`StiffeningResult.predict`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..intervals import LEVEL, central, central_band
from .model import LAW_TEXT

__all__ = ["StiffeningResult", "draw_summary", "parameter_table"]


def draw_summary(x, level):
    """Median, sd and the central ``level`` interval (lo, hi) of draws ``x``."""
    lo, hi = central(x, level)
    return float(np.median(x)), float(np.std(x, ddof=1)), float(lo), float(hi)


@dataclass
class StiffeningResult:
    """Result of :func:`fit_stiffening`.

    Attributes
    ----------
    identifiable
        True when the two exponentials are resolved (double-law checks 1-6 of
        :mod:`~palpbayes.stiffening.selection`, convergence included).
    message
        One paragraph: what was found and, for a simpler law, why the richer ones failed.
    preferred
        ``"double"``, ``"single"`` or ``"constant"`` (no stiffening detected): the law to use
        for prediction.
    double, single, constant
        Parameter tables (``parameter, unit, median, sd, lo, hi``; 90 % intervals) of the
        double law (c1 [Pa], c2 [1/s], c3 [Pa], c4 [1/s], sigma_x [Pa]), of
        E = c0 + c1·e^(c2·t) (c0, c1 [Pa], c2 [1/s], sigma_x [Pa]) and of E = c0 (c0,
        sigma_x [Pa]).
    draws, single_draws, constant_draws
        Posterior draws in the same units (keys as the ``parameter`` column).
    bic_double, bic_single, bic_constant
        BIC of each law (lower is better).
    converged
        The preferred law's sampler passed R-hat/ESS (``converged_laws`` has all three).
    n_points, n_distinct
        Estimates used and distinct rest times.
    reasons, single_reasons
        Failed checks of the double and of the single law.
    single_identifiable
        The single exponential passes its checks (:mod:`~palpbayes.stiffening.selection`).
    E_mean_pa, E_sd_pa
        [Pa] Mean and sd (ddof 1) of the estimates.
    """

    identifiable: bool
    message: str
    preferred: str
    double: pd.DataFrame
    single: pd.DataFrame
    draws: dict[str, np.ndarray]
    single_draws: dict[str, np.ndarray]
    bic_double: float
    bic_single: float
    converged: bool
    n_points: int
    n_distinct: int
    reasons: list[str] = field(default_factory=list)
    single_identifiable: bool = False
    single_reasons: list[str] = field(default_factory=list)
    constant: pd.DataFrame | None = None
    constant_draws: dict[str, np.ndarray] = field(default_factory=dict)
    bic_constant: float = np.nan
    converged_laws: dict[str, bool] = field(default_factory=dict)
    E_mean_pa: float = np.nan
    E_sd_pa: float = np.nan

    @property
    def stiffening_detected(self) -> bool:
        """False when the outcome is a constant modulus (no stiffening law passed its checks)."""
        return self.preferred != "constant"

    def table_of(self, model: str | None = None) -> pd.DataFrame:
        """Parameter table of ``model`` ("double", "single", "constant"; default: preferred)."""
        model = model or self.preferred
        return {"double": self.double, "single": self.single, "constant": self.constant}[model]

    @property
    def law(self) -> str:
        """The preferred law as an equation, e.g. ``E(t) = c0 + c1·exp(c2·t)``."""
        return LAW_TEXT[self.preferred]

    def row(self) -> dict:
        """One row of ``stiffening.csv``: verdict, BICs and the preferred law's medians."""
        tab = self.table_of().set_index("parameter")["median"]
        out = {"n_points": self.n_points, "n_distinct": self.n_distinct,
               "identifiable": self.identifiable, "preferred": self.preferred}
        for k in ("c0", "c1", "c2", "c3", "c4", "sigma_x"):
            out[k] = float(tab[k]) if k in tab.index else np.nan
        out.update({"bic_double": self.bic_double, "bic_single": self.bic_single,
                    "bic_constant": self.bic_constant,
                    "stiffening_detected": self.stiffening_detected,
                    "single_identifiable": self.single_identifiable,
                    "E_mean_pa": self.E_mean_pa, "E_sd_pa": self.E_sd_pa,
                    "converged": self.converged, "message": self.message})
        return out

    def predict(self, t: ArrayLike, level: float = LEVEL, model: str | None = None
                ) -> pd.DataFrame:
        """Posterior of the mean curve E(t) [Pa] on rest times ``t`` [s] (preferred law)."""
        model = model or self.preferred
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if model == "double":
            d = self.draws
            curves = (d["c1"][:, None] * np.exp(d["c2"][:, None] * t)
                      + d["c3"][:, None] * np.exp(d["c4"][:, None] * t))
        elif model == "constant":
            curves = np.repeat(self.constant_draws["c0"][:, None], t.size, axis=1)
        else:
            d = self.single_draws
            curves = d["c0"][:, None] + d["c1"][:, None] * np.exp(d["c2"][:, None] * t)
        lo, med, hi = central_band(curves, level)
        return pd.DataFrame({"t_s": t, "median_pa": med, "lo_pa": lo, "hi_pa": hi})


def parameter_table(draws: dict, units: dict, level: float) -> pd.DataFrame:
    """One row per parameter of ``draws``: unit, median, sd and the ``level`` interval."""
    rows = []
    for k, x in draws.items():
        med, sd, lo, hi = draw_summary(x, level)
        rows.append({"parameter": k, "unit": units[k], "median": med, "sd": sd, "lo": lo,
                     "hi": hi})
    return pd.DataFrame(rows)
