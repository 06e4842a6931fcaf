"""Online estimation: how the interval of E narrows as the tip goes deeper."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .style import KPA, METHOD_COLORS, MM, MN

__all__ = ["plot_replay"]


def plot_replay(history: pd.DataFrame, *, stop_n: int | None = None,
                target: float | None = None, truth: float | None = None,
                level: float = 0.9, title: str = "") -> Figure:
    """E with its interval against depth during a replayed (or live) palpation.

    Parameters
    ----------
    history
        One row per update: ``depth_m``, ``E_pa``, ``E_lo_pa``, ``E_hi_pa``,
        ``rel_half_width``, ``peak_force_n``, ``n`` (:data:`palpbayes.online.HISTORY_COLUMNS`).
    stop_n
        Sample count at which the stopping rule fired (a vertical line), or None.
    target
        Relative half-width of the stopping rule (a horizontal line on the lower panel).
    truth
        [Pa] True modulus of a simulated trace (a horizontal line).
    level
        Probability content of the intervals (for the legend).
    title
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Upper panel: E [kPa] and its interval vs depth [mm]; lower panel: the interval's
        relative half-width [%] (log scale) with the peak force [mN] on a second axis.
    """
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    h = history[history["depth_m"] > 0]
    d = h["depth_m"].to_numpy() * MM
    color = METHOD_COLORS["bayes"]
    top.fill_between(d, h["E_lo_pa"] * KPA, h["E_hi_pa"] * KPA, color=color, alpha=0.25,
                     lw=0, label=f"{100 * level:g} % interval")
    top.plot(d, h["E_pa"] * KPA, color=color, lw=1.5, label="posterior median")
    if truth is not None:
        top.axhline(truth * KPA, color=METHOD_COLORS["truth"], ls="--", lw=1, label="true E")
    top.set_ylabel("E [kPa]")
    bottom.semilogy(d, 100 * h["rel_half_width"], color=color, lw=1.5,
                    label="relative half-width")
    if target is not None:
        bottom.axhline(100 * target, color="k", ls=":", lw=1, label=f"target ±{100 * target:g} %")
    force_ax = bottom.twinx()
    force_ax.plot(d, h["peak_force_n"] * MN, color=METHOD_COLORS["data"], lw=1,
                  label="peak force")
    force_ax.set_ylabel("peak force [mN]")
    if stop_n is not None and (h["n"] == stop_n).any():
        ds = float(h.loc[h["n"] == stop_n, "depth_m"].iloc[0]) * MM
        for ax in (top, bottom):
            ax.axvline(ds, color="k", lw=1, alpha=0.6)
        top.annotate("stop", (ds, 1.0), xycoords=("data", "axes fraction"), ha="left",
                     va="top", fontsize=8, xytext=(3, -3), textcoords="offset points")
    bottom.set_xlabel("depth below the estimated surface [mm]")
    bottom.set_ylabel("half-width [%]")
    lines = bottom.get_legend_handles_labels()
    flines = force_ax.get_legend_handles_labels()
    bottom.legend(lines[0] + flines[0], lines[1] + flines[1], fontsize=8, loc="upper right")
    top.legend(fontsize=8, loc="upper right")
    if np.isfinite(d).any():
        top.set_xlim(0, float(np.nanmax(d)))
    if title:
        fig.suptitle(title)
    return fig
