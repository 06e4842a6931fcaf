"""Palpation and compression like for like: a material's Instron-equivalent modulus.

A group's pooled Bayesian estimate (:mod:`palpbayes.pooling`) is the material's Young's modulus
E.  The Instron reports what its compression test reads, c·E, with c = 1 between lubricated
platens and c(nu, block) > 1 between bonded ones (:mod:`palpbayes.twin.compression`).  When
the traces were fitted with the specimen's twin (a footprint known), each pooled draw of a new
specimen's E is turned into that reading with its own Poisson ratio, as the per-trace rows are
(:mod:`palpbayes.bayes.instron`), and set beside the Instron mean:

* ``E_instron_pa``, ``E_instron_new_lo_pa`` … ``E_instron_new_hi_pa``: the median and the 90 %
  interval of a new specimen's compression reading (``--platens unknown``: from the
  lubricated draws' lower end to the bonded draws' upper end);
* ``gt_in_instron_interval``: the Instron mean inside that interval;
* ``instron_rel_err_pct`` = 100·(GT − E_instron)/GT, the paper's convention.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..bayes.budget import BudgetSpec, nu_nodes
from ..bayes.instron import instron_bonded_draws, instron_columns

__all__ = ["INSTRON_GROUP_COLUMNS", "instron_group_columns", "instron_gt_columns"]

#: comparison.csv columns of the Instron-equivalent modulus (NaN without a specimen).
INSTRON_GROUP_COLUMNS = ["platens", "E_instron_pa", "E_instron_new_lo_pa",
                         "E_instron_new_hi_pa", "gt_in_instron_interval", "instron_rel_err_pct"]


def instron_group_columns(E_new: np.ndarray, nu: np.ndarray | None, model, budget: BudgetSpec,
                          platens: str) -> dict:
    """The Instron-equivalent columns of a pooled group from its new-specimen draws ``E_new``
    [Pa] with their Poisson ratios ``nu``, for the block of ``model`` (its ``specimen``); {}
    without a specimen or without the budget's nu draws."""
    if model is None or getattr(model, "specimen", None) is None or nu is None:
        return {}
    bonded = instron_bonded_draws(E_new, nu, model.specimen, nu_nodes(budget, model.nu))
    cols = instron_columns(E_new, bonded, platens)
    return {"platens": cols["platens"], "E_instron_pa": cols["E_instron_pa"],
            "E_instron_new_lo_pa": cols["E_instron_lo_pa"],
            "E_instron_new_hi_pa": cols["E_instron_hi_pa"]}


def instron_gt_columns(row: dict, gt: pd.DataFrame | None, material: str) -> dict:
    """``gt_in_instron_interval`` and ``instron_rel_err_pct`` of a row that has the
    Instron-equivalent columns and a ground truth for ``material``; {} otherwise."""
    e = row.get("E_instron_pa", np.nan)
    if gt is None or gt.empty or e is None or not np.isfinite(e):
        return {}
    hit = gt[gt["material"].astype(str).str.lower() == str(material).lower()]
    if hit.empty:
        return {}
    g = float(hit["E_mean_pa"].iloc[0])
    lo, hi = row["E_instron_new_lo_pa"], row["E_instron_new_hi_pa"]
    return {"gt_in_instron_interval": bool(lo <= g <= hi),
            "instron_rel_err_pct": 100.0 * (g - e) / g}
