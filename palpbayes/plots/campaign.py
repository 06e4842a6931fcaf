"""Campaign figures: ground truth vs the methods per material × tip, and a group's forest plot."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..campaign.results import MATERIAL_ORDER, TIP_ORDER, ordered
from .style import KPA, METHOD_COLORS, METHOD_LABELS, fig_ax

__all__ = ["plot_comparison", "plot_forest"]


def plot_comparison(
    comparison: pd.DataFrame,
    *,
    ax: Axes | None = None,
    methods: Sequence[str] = ("lsq", "bayes"),
    show_paper: bool = True,
    show_new: bool = True,
) -> Figure:
    """Ground truth vs least squares vs Bayes for every material × tip [kPa].

    One group of columns per material (ground truth mean ± sd as a grey band across the
    group), one slot per tip, methods side by side.  Thick bars are each method's interval of
    the material's modulus (``E_lo_pa``–``E_hi_pa``); thin bars the interval for a new
    specimen (``E_new_lo_pa``–``E_new_hi_pa``: least squares' t prediction interval, Bayes'
    posterior predictive), the quantity to compare with the spread of the Instron tests.  The
    paper's robot estimate is drawn as mean ± sd where known.

    Parameters
    ----------
    comparison
        ``comparison.csv``: ``material, tip, method, E_pa, E_lo_pa, E_hi_pa`` and optionally
        ``E_new_pa, E_new_lo_pa, E_new_hi_pa, gt_E_pa, gt_sd_pa, paper_E_pa, paper_sd_pa``.
    ax
        Axes to draw on (default: a new 10 × 4.5 in figure).
    methods
        Methods to draw, in order.
    show_paper, show_new
        Draw the paper's numbers / the new-specimen intervals.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = fig_ax(ax, (10.0, 4.5))
    df = comparison.copy()
    materials = ordered(df["material"], MATERIAL_ORDER)
    tips = ordered(df["tip"], TIP_ORDER)
    slots = list(methods) + (["paper"] if show_paper and "paper_E_pa" in df else [])
    width = 0.8 / max(len(slots), 1)
    xticks, xlabels, handles = [], [], {}
    x0 = 0.0
    for mat in materials:
        sub = df[df["material"] == mat]
        group_tips = [t for t in tips if t in set(sub["tip"])]
        lo_x, hi_x = x0 - 0.5, x0 + len(group_tips) - 0.5
        if "gt_E_pa" in sub and sub["gt_E_pa"].notna().any():
            gt = float(sub["gt_E_pa"].dropna().iloc[0]) * KPA
            sd = float(sub["gt_sd_pa"].dropna().iloc[0]) * KPA if "gt_sd_pa" in sub and \
                sub["gt_sd_pa"].notna().any() else 0.0
            ax.fill_between([lo_x, hi_x], gt - sd, gt + sd, color="0.88", lw=0, zorder=0)
            ax.hlines(gt, lo_x, hi_x, color=METHOD_COLORS["gt"], lw=1.2, zorder=1)
            handles["gt"] = (Patch(facecolor="0.88", edgecolor=METHOD_COLORS["gt"]),
                             f"{METHOD_LABELS['gt']} (mean ± sd)")
        for j, tip in enumerate(group_tips):
            x = x0 + j
            xticks.append(x)
            xlabels.append(tip)
            for k, m in enumerate(slots):
                xm = x - 0.4 + width * (k + 0.5)
                color = METHOD_COLORS.get(m, "k")
                if m == "paper":
                    row = sub[sub["tip"] == tip]
                    if row.empty or not np.isfinite(row["paper_E_pa"].astype(float)).any():
                        continue
                    pe = float(row["paper_E_pa"].dropna().iloc[0]) * KPA
                    ps = float(row["paper_sd_pa"].dropna().iloc[0]) * KPA \
                        if "paper_sd_pa" in row and row["paper_sd_pa"].notna().any() else 0.0
                    ax.errorbar([xm], [pe], yerr=[ps], fmt="D", ms=4, color=color,
                                capsize=2, lw=1.0, mfc="white")
                    handles[m] = (Line2D([], [], marker="D", color=color, mfc="white", ms=4),
                                  f"{METHOD_LABELS[m]} mean ± sd")
                    continue
                row = sub[(sub["tip"] == tip) & (sub["method"] == m)]
                if row.empty:
                    continue
                r = row.iloc[0]
                e = r["E_pa"] * KPA
                if show_new and "E_new_lo_pa" in r and np.isfinite(r["E_new_lo_pa"]):
                    ax.vlines(xm, r["E_new_lo_pa"] * KPA, r["E_new_hi_pa"] * KPA,
                              color=color, lw=1.0, zorder=2)
                    handles["new"] = (Line2D([], [], color="0.3", lw=1.0),
                                      "thin: 90 % interval for a new specimen")
                ax.vlines(xm, r["E_lo_pa"] * KPA, r["E_hi_pa"] * KPA, color=color, lw=3.0,
                          zorder=3)
                ax.plot([xm], [e], "o", ms=4.5, color=color, mec="white", mew=0.6, zorder=4)
                handles[m] = (Line2D([], [], color=color, lw=3.0, marker="o", ms=4.5,
                                     mec="white"), f"{METHOD_LABELS.get(m, m)} (interval)")
        ax.text((lo_x + hi_x) / 2, 1.0, mat, transform=ax.get_xaxis_transform(),
                ha="center", va="bottom", fontweight="bold")
        x0 += len(group_tips) + 0.6
        if mat != materials[-1]:
            ax.axvline(x0 - 0.8, color="0.7", lw=0.6)
    ax.set_xticks(xticks, xlabels)
    ax.set_xlim(-0.6, x0 - 0.5)
    ax.set_ylabel("Young's modulus, E [kPa]")
    order = ["gt", *methods, "new", "paper"]
    hs = [handles[k] for k in order if k in handles]
    ax.legend([h for h, _ in hs], [lab for _, lab in hs], loc="upper left", fontsize="x-small",
              frameon=False, ncol=2)
    ax.margins(y=0.15)
    return fig


def plot_forest(
    summary: pd.DataFrame,
    pooled: Mapping[str, float] | pd.Series | None = None,
    *,
    gt: tuple[float, float] | None = None,
    ax: Axes | None = None,
    methods: Sequence[str] = ("lsq", "bayes"),
    title: str | None = None,
) -> Figure:
    """Per-trace intervals of E for one material × tip, with the pooled estimate [kPa].

    Parameters
    ----------
    summary
        Rows of ``summary.csv`` for one group: ``trace_id, method, E_pa, E_lo_pa, E_hi_pa``.
    pooled
        The pooled Bayesian result: ``E_pa, E_lo_pa, E_hi_pa`` (material mean) and optionally
        ``E_new_pa, E_new_lo_pa, E_new_hi_pa`` (a new specimen).
    gt
        (mean, sd) [Pa] of the ground truth, drawn as a band.
    ax
        Axes to draw on.
    methods
        Per-trace methods to draw.
    title
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ids = list(dict.fromkeys(summary["trace_id"]))
    fig, ax = fig_ax(ax, (5.0, 0.4 * len(ids) + 1.8))
    n = len(ids)
    ypos = {tid: n + 1 - i for i, tid in enumerate(ids)}  # pooled rows at the bottom
    off = {m: (k - (len(methods) - 1) / 2) * 0.22 for k, m in enumerate(methods)}
    seen = set()
    if gt is not None and np.isfinite(gt[0]):
        g, s = gt[0] * KPA, (gt[1] if np.isfinite(gt[1]) else 0.0) * KPA
        ax.axvspan(g - s, g + s, color="0.88", lw=0, zorder=0)
        ax.axvline(g, color=METHOD_COLORS["gt"], lw=1.2, zorder=1,
                   label="Instron GT, mean ± sd")
    for _, r in summary.iterrows():
        m = r["method"]
        if m not in off:
            continue
        y = ypos[r["trace_id"]] + off[m]
        c = METHOD_COLORS.get(m, "k")
        ax.hlines(y, r["E_lo_pa"] * KPA, r["E_hi_pa"] * KPA, color=c, lw=2.0)
        lab = None if m in seen else f"{METHOD_LABELS.get(m, m)}, per trace"
        seen.add(m)
        ax.plot([r["E_pa"] * KPA], [y], "o", ms=4, color=c, mec="white", mew=0.5, label=lab)
    labels = {v: k for k, v in ypos.items()}
    if pooled is not None:
        p = pd.Series(pooled)
        c = METHOD_COLORS["bayes"]
        ax.hlines(0.9, p["E_lo_pa"] * KPA, p["E_hi_pa"] * KPA, color=c, lw=3.0)
        ax.plot([p["E_pa"] * KPA], [0.9], "D", ms=6, color=c, mec="white",
                label="pooled: material")
        labels[0.9] = "pooled mean"
        if "E_new_lo_pa" in p and np.isfinite(p["E_new_lo_pa"]):
            cn = METHOD_COLORS["pooled"]
            ax.hlines(0.2, p["E_new_lo_pa"] * KPA, p["E_new_hi_pa"] * KPA, color=cn, lw=3.0)
            ax.plot([p.get("E_new_pa", p["E_pa"]) * KPA], [0.2], "D", ms=6, color=cn,
                    mec="white", label="pooled: new spec.")
            labels[0.2] = "new specimen"
        ax.axhline(1.5, color="0.7", lw=0.6)
    ys = sorted(labels)
    ax.set_yticks(ys, [labels[y] for y in ys], fontsize="small")
    ax.set_ylim(-0.4, n + 1.6 + 0.5 * math.ceil(len(ax.get_legend_handles_labels()[1]) / 2))
    ax.set_xlabel("Young's modulus, E [kPa]")
    if title:
        ax.set_title(title, fontsize="medium")
    ax.legend(loc="upper center", fontsize="xx-small", ncol=2, frameon=False)
    return fig
