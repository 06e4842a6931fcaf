"""Finite-thickness figures: the paper's robot-vs-Instron gap against the tool's prediction, and
a campaign's half-space and layer estimates side by side."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..campaign.results import MATERIAL_ORDER, TIP_ORDER, ordered
from .groups import material_tip_columns
from .style import KPA, METHOD_COLORS, METHOD_LABELS, fig_ax

__all__ = ["plot_gap", "plot_strain_factors", "plot_halfspace_vs_layer"]

_LAYER = "#E69F00"  # orange: what the layer model predicts


def plot_gap(gap: pd.DataFrame, *, ax: Axes | None = None) -> Figure:
    """The paper's robot estimate against the Instron, and what the tool's models predict.

    Per material × tip (grouped by tip): the published ratio E_robot/E_Instron − 1 with its
    90 % interval (the two published sd's); the block as tested, its finite-element twin at
    nu 0.3 from a free to a bonded base between lubricated platens (dark bar), and the whole
    modelled range (base × nu 0.1–0.35 × compliance × lubricated or bonded platens, Hertz for
    the sphere; light bar); beside it, outlined, that range for a layer of infinite width and
    an exact Instron (the prediction before the twin).

    Parameters
    ----------
    gap
        :func:`palpbayes.gap.gap_table` (``gap.csv``).
    ax
        Axes to draw on (default: a new 9 × 4 in figure).
    """
    fig, ax = fig_ax(ax, (9.0, 4.0))
    tips = ordered(gap["tip"], TIP_ORDER)
    mats = ordered(gap["material"], MATERIAL_ORDER)
    xt, xl = [], []
    x = 0.0
    for tip in tips:
        for mat in mats:
            r = gap[(gap["tip"] == tip) & (gap["material"] == mat)]
            if r.empty:
                continue
            r = r.iloc[0]
            ax.bar(x + 0.32, r["layer_hi_pct"] - r["layer_lo_pct"], bottom=r["layer_lo_pct"],
                   width=0.16, facecolor="none", edgecolor="0.45", lw=0.8)
            ax.bar(x, r["predicted_hi_pct"] - r["predicted_lo_pct"],
                   bottom=r["predicted_lo_pct"], width=0.55, color=_LAYER, alpha=0.25, lw=0)
            twin = [100 * ((1 + r[f"thickness_{b}_pct"] / 100) * (1 + r[f"width_{b}_pct"] / 100)
                           - 1) for b in ("free", "bonded")]
            lo, hi = min(twin), max(twin)
            ax.bar(x, max(hi - lo, 0.4), bottom=lo, width=0.3, color=_LAYER, lw=0)
            ax.errorbar([x], [r["observed_pct"]],
                        yerr=[[r["observed_pct"] - r["observed_lo_pct"]],
                              [r["observed_hi_pct"] - r["observed_pct"]]],
                        fmt="o", ms=5, color=METHOD_COLORS["paper"], capsize=3, zorder=3,
                        mfc=METHOD_COLORS["paper"] if r["explained"] else "white")
            xt.append(x)
            xl.append(f"{mat}\n{tip}")
            x += 1.0
        x += 0.6
    ax.axhline(0.0, color="0.3", lw=0.7)
    top = float(np.nanmax(gap[["layer_hi_pct", "predicted_hi_pct", "observed_hi_pct"]]))
    bottom = float(np.nanmin(gap[["predicted_lo_pct", "observed_lo_pct"]]))
    ax.set_ylim(bottom - 5.0, top + 0.45 * (top - bottom))  # room for the legend
    ax.set_xticks(xt, xl, fontsize="small")
    ax.set_ylabel("robot ÷ Instron − 1 [%]")
    n_ok, n_layer = int(gap["explained"].sum()), int(gap["explained_layer"].sum())
    ax.set_title(f"The paper's robot estimates against its Instron: the specimen as tested "
                 f"explains {n_ok} of {len(gap)} (the infinite layer {n_layer})",
                 fontsize="medium")
    ax.legend(handles=[
        Line2D([], [], marker="o", ls="", color=METHOD_COLORS["paper"],
               label="published (90 % interval from both sd's; filled: inside the prediction)"),
        Patch(color=_LAYER, label="the block's twin, free to bonded base (nu 0.3)"),
        Patch(color=_LAYER, alpha=0.25,
              label="everything modelled (twin, base, nu 0.1–0.35, compliance, platens, Hertz)"),
        Patch(facecolor="none", edgecolor="0.45",
              label="the same with an infinite layer and an exact Instron")],
        fontsize="x-small", frameon=False, loc="upper center", ncol=2)
    return fig


def plot_strain_factors(strain: pd.DataFrame, *, ax: Axes | None = None) -> Figure:
    """What finite strain multiplies the paper's robot ÷ Instron ratio by, per foam and tip.

    One column per foam of :data:`palpbayes.gap_strain.FOAMS`; per tip a vertical bar over
    the paper's three blocks and both bases (``strain_factor`` − 1 [%] of ``gap_strain.csv``):
    above 0 the foam makes the robot read stiffer against the Instron than a linear block does.

    Parameters
    ----------
    strain
        :func:`palpbayes.gap_strain.strain_table` (``gap_strain.csv``).
    ax
        Axes to draw on (default: a new 9 × 4 in figure).
    """
    fig, ax = fig_ax(ax, (9.0, 4.0))
    foams = list(dict.fromkeys(strain["foam"]))
    tips = ordered(strain["tip"], TIP_ORDER)
    colors = {t: c for t, c in zip(tips, ("#0072B2", "#009E73", "#CC79A7"), strict=False)}
    width = 0.8 / max(len(tips), 1)
    for i, foam in enumerate(foams):
        for j, tip in enumerate(tips):
            f = 100.0 * (strain[(strain["foam"] == foam) & (strain["tip"] == tip)]
                         ["strain_factor"] - 1.0)
            if f.empty:
                continue
            x = i - 0.4 + (j + 0.5) * width
            ax.bar(x, max(f.max() - f.min(), 0.4), bottom=f.min(), width=0.8 * width,
                   color=colors[tip], lw=0, label=tip if i == 0 else None)
    ax.use_sticky_edges = False  # a bar's foot is data, not the frame: keep a margin below
    ax.axhline(0.0, color="0.3", lw=0.7)
    labels = [f.replace("hyperfoam ", "").replace("neo-Hookean ", "neo-H.\n")
              .replace(" alpha ", "\nα ").replace("nu ", "ν ") for f in foams]
    ax.set_xticks(range(len(foams)), labels, fontsize="x-small")
    ax.set_xlabel("the foam: hyperfoam (ν, α; α = 2 nearly linear, larger: a plateau) or a "
                  "compressible neo-Hookean solid", fontsize="small")
    ax.set_ylabel("robot ÷ Instron against a linear block [%]")
    ax.set_title("A softening foam raises the ratio, a stiffening one lowers it; the tips move "
                 "together", fontsize="medium")
    ax.legend(fontsize="x-small", frameon=False, ncol=len(tips), loc="upper left")
    return fig


def plot_halfspace_vs_layer(comparison: pd.DataFrame, *, ax: Axes | None = None) -> Figure:
    """A campaign's estimates per material × tip [kPa]: the paper's half-space least squares,
    the same fits read as a free and a bonded layer, and the Bayesian layer model's interval for
    a new specimen, against the Instron mean ± sd.

    Parameters
    ----------
    comparison
        ``comparison.csv`` with ``E_free_pa``/``E_bonded_pa`` (group means of the traces).
    ax
        Axes to draw on (default: a new 10 × 4.5 in figure).
    """
    fig, ax = fig_ax(ax, (10.0, 4.5))

    def draw(x: float, g: pd.DataFrame) -> None:
        if "lsq" in g.index:
            r = g.loc["lsq"]
            ax.plot([x - 0.2], [r["E_pa"] * KPA], "s", ms=5, color=METHOD_COLORS["lsq"])
            alt = [r.get(c, np.nan) for c in ("E_free_pa", "E_bonded_pa")]
            if np.all(np.isfinite(alt)):
                ax.vlines(x - 0.05, min(alt) * KPA, max(alt) * KPA, color=_LAYER, lw=4)
        if "bayes" in g.index:
            r = g.loc["bayes"]
            ax.errorbar([x + 0.15], [r["E_new_pa"] * KPA],
                        yerr=[[(r["E_new_pa"] - r["E_new_lo_pa"]) * KPA],
                              [(r["E_new_hi_pa"] - r["E_new_pa"]) * KPA]],
                        fmt="o", ms=5, color=METHOD_COLORS["bayes"], capsize=3)

    material_tip_columns(ax, comparison, draw)
    ax.set_ylabel("E [kPa]")
    ax.set_title("Half-space (the paper's) and layer estimates against the Instron",
                 fontsize="medium")
    ax.legend(handles=[
        Patch(facecolor="0.88", edgecolor=METHOD_COLORS["gt"],
              label=f"{METHOD_LABELS['gt']} (mean ± sd)"),
        Line2D([], [], marker="s", ls="", color=METHOD_COLORS["lsq"],
               label="least squares, half-space (the paper's method), mean"),
        Line2D([], [], color=_LAYER, lw=4, label="the same fits read as a free to bonded layer"),
        Line2D([], [], marker="o", color=METHOD_COLORS["bayes"],
               label="Bayes with the layer: a new specimen, 90 %")],
        fontsize="x-small", frameon=False, loc="upper left")
    return fig
