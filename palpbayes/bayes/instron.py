"""The Instron-equivalent modulus: what a compression test of the palpated block would report.

A palpation fit with the specimen's twin (:mod:`palpbayes.twin`) estimates the material's
Young's modulus E.  A compression test of the same block reports E_app = c·E, with c = 1
between lubricated (frictionless) platens and c(nu, block) > 1 between bonded ones
(:func:`palpbayes.twin.compression_factor`).  Each posterior draw of E (with the budget,
:mod:`palpbayes.bayes.budget`) carries its own Poisson ratio, so each gets its own c: the
draws of E_instron = c(nu)·E carry the posterior, the budget and the platens' uncertainty
together.  c is computed by the twin at the budget's nodes of nu and interpolated.

``platens`` (``--platens``):

* ``lubricated``: E_instron = E;
* ``bonded``: E_instron = c_bonded(nu)·E;
* ``unknown`` (default): the median of the two sets of draws pooled, and the interval from the
  lubricated draws' lower end to the bonded draws' upper end (it spans both).

With a material misfit the full interval of E is wider than its budget interval (the model
form, :mod:`palpbayes.bayes.modelform`); the Instron interval's ends are widened by the same
factors.
"""

from __future__ import annotations

import math

import numpy as np

from ..intervals import central, hull
from ..twin import Specimen, compression_factor

__all__ = ["instron_bonded_draws", "instron_columns", "INSTRON_COLUMNS"]

#: ``summary.csv`` columns of a Bayesian row with a specimen (NaN without one).
INSTRON_COLUMNS = ("platens", "E_instron_pa", "E_instron_lo_pa", "E_instron_hi_pa")


def instron_bonded_draws(E_total: np.ndarray, nu: np.ndarray, specimen: Specimen,
                         nu_grid: np.ndarray) -> np.ndarray:
    """Draws of c_bonded(nu)·E [Pa] for draws ``E_total`` [Pa] with Poisson ratios ``nu``
    [-] (same shape), c interpolated on ``nu_grid``."""
    grid = np.unique(np.asarray(nu_grid, dtype=float))
    c = np.array([compression_factor(specimen, float(v), "bonded") for v in grid])
    nu = np.asarray(nu, dtype=float)
    factor = np.interp(nu, grid, c) if grid.size > 1 else np.full(nu.shape, c[0])
    return np.asarray(E_total, dtype=float) * factor


def instron_columns(E_total: np.ndarray, E_bonded: np.ndarray | None, platens: str,
                    widen: tuple[float, float] = (1.0, 1.0), center: float = 1.0) -> dict:
    """``platens``, ``E_instron_pa`` and its interval ``E_instron_lo_pa``..``_hi_pa`` [Pa]
    (module docstring); NaN without bonded draws (no specimen).  ``widen`` = (full lower end
    / budget lower end, full upper end / budget upper end) of E; ``center`` = the row's E at
    the stated inputs / the median of the ``E_total`` draws: the headline is moved by it as
    the row's E is (a one-sided budget moves the draws, not the headline; with lubricated
    platens ``E_instron_pa`` is then the row's ``E_pa``), and the interval holds it."""
    nan = {"platens": "", "E_instron_pa": math.nan, "E_instron_lo_pa": math.nan,
           "E_instron_hi_pa": math.nan}
    if E_bonded is None:
        return nan
    lub = np.ravel(E_total)
    bond = np.ravel(E_bonded)
    if platens == "lubricated":
        pool, (lo, hi) = lub, central(lub)
    elif platens == "bonded":
        pool, (lo, hi) = bond, central(bond)
    else:
        pool = np.concatenate([lub, bond])
        lo, hi = central(lub)[0], central(bond)[1]
    mid = float(np.median(pool)) * center
    lo, hi = hull((float(lo) * widen[0], float(hi) * widen[1]), (mid, mid))
    return {"platens": platens, "E_instron_pa": mid, "E_instron_lo_pa": lo,
            "E_instron_hi_pa": hi}
