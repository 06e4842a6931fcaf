"""The specimen as tested: palpation and compression set side by side, like for like."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .groups import material_tip_columns
from .style import KPA, METHOD_COLORS, METHOD_LABELS, fig_ax

__all__ = ["plot_specimen_as_tested"]

_INSTRON = "#D55E00"  # vermilion: what a compression test of the block would read


def plot_specimen_as_tested(comparison: pd.DataFrame, *, ax: Axes | None = None) -> Figure:
    """Per material × tip [kPa]: the Bayesian interval of a new specimen's E (the block's
    twin) and of what a compression test of its block would read between the run's platens
    (``E_instron_new_*``), against the Instron mean ± sd; the paper's half-space least squares
    for scale.

    Parameters
    ----------
    comparison
        ``comparison.csv`` with the Instron-equivalent columns
        (:mod:`palpbayes.campaign.instron`).
    ax
        Axes to draw on (default: a new 10 × 4.5 in figure).
    """
    fig, ax = fig_ax(ax, (10.0, 4.5))

    def draw(x: float, g: pd.DataFrame) -> None:
        if "lsq" in g.index and np.isfinite(g.loc["lsq", "E_pa"]):
            ax.plot([x - 0.25], [g.loc["lsq", "E_pa"] * KPA], "s", ms=5,
                    color=METHOD_COLORS["lsq"])
        if "bayes" in g.index:
            r = g.loc["bayes"]
            ax.errorbar([x - 0.05], [r["E_new_pa"] * KPA],
                        yerr=[[(r["E_new_pa"] - r["E_new_lo_pa"]) * KPA],
                              [(r["E_new_hi_pa"] - r["E_new_pa"]) * KPA]],
                        fmt="o", ms=5, color=METHOD_COLORS["bayes"], capsize=3)
            if np.isfinite(r.get("E_instron_pa", np.nan)):
                ax.errorbar([x + 0.2], [r["E_instron_pa"] * KPA],
                            yerr=[[(r["E_instron_pa"] - r["E_instron_new_lo_pa"]) * KPA],
                                  [(r["E_instron_new_hi_pa"] - r["E_instron_pa"]) * KPA]],
                            fmt="D", ms=5, color=_INSTRON, capsize=3)

    material_tip_columns(ax, comparison, draw)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.3 * (hi - lo))  # room for the legend above the bars
    ax.set_ylabel("E [kPa]")
    ax.set_title("The specimen as tested: palpation and compression like for like",
                 fontsize="medium")
    ax.legend(handles=[
        Patch(facecolor="0.88", edgecolor=METHOD_COLORS["gt"],
              label=f"{METHOD_LABELS['gt']} (mean ± sd: what the compression test read)"),
        Line2D([], [], marker="s", ls="", color=METHOD_COLORS["lsq"],
               label="least squares, half-space (the paper's method), mean"),
        Line2D([], [], marker="o", color=METHOD_COLORS["bayes"],
               label="Bayes, the block's twin: E of a new specimen, 90 %"),
        Line2D([], [], marker="D", color=_INSTRON,
               label="... what its compression test would read (the run's platens), 90 %")],
        fontsize="x-small", frameon=False, loc="upper left", ncol=2)
    return fig
