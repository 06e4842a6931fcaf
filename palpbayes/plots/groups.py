"""One column per material × tip against the material's Instron band: the layout the
campaign figures share (:func:`~palpbayes.plots.layer.plot_halfspace_vs_layer`,
:func:`~palpbayes.plots.twin.plot_specimen_as_tested`)."""

from __future__ import annotations

from collections.abc import Callable

import pandas as pd
from matplotlib.axes import Axes

from ..campaign.results import MATERIAL_ORDER, TIP_ORDER, ordered
from .style import KPA, METHOD_COLORS

__all__ = ["material_tip_columns"]


def material_tip_columns(ax: Axes, comparison: pd.DataFrame,
                         draw: Callable[[float, pd.DataFrame], None]) -> None:
    """Draw ``comparison`` (``comparison.csv``) one column per material × tip, materials and
    tips in the report's order, a gap between materials.

    Behind each material's columns: its Instron mean ± sd [kPa] (``gt_E_pa``, ``gt_sd_pa``)
    as a grey band and a line.  ``draw(x, rows)`` draws one column at ``x`` from its rows
    indexed by ``method``; the x ticks name material and tip.
    """
    mats = ordered(comparison["material"], MATERIAL_ORDER)
    tips = ordered(comparison["tip"], TIP_ORDER)
    xt, xl = [], []
    x = 0.0
    for mat in mats:
        sub = comparison[comparison["material"] == mat]
        group = [t for t in tips if t in set(sub["tip"])]
        if "gt_E_pa" in sub and sub["gt_E_pa"].notna().any():
            gt = float(sub["gt_E_pa"].dropna().iloc[0]) * KPA
            sd = float(sub["gt_sd_pa"].fillna(0).iloc[0]) * KPA if "gt_sd_pa" in sub else 0.0
            ax.fill_between([x - 0.5, x + len(group) - 0.5], gt - sd, gt + sd, color="0.88",
                            lw=0, zorder=0)
            ax.hlines(gt, x - 0.5, x + len(group) - 0.5, color=METHOD_COLORS["gt"], lw=1.2)
        for tip in group:
            draw(x, sub[sub["tip"] == tip].set_index("method"))
            xt.append(x)
            xl.append(f"{mat}\n{tip}")
            x += 1.0
        x += 0.5
    ax.set_xticks(xt, xl, fontsize="small")
