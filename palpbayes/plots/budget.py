"""The uncertainty budget: each input's share of the variance of ln E."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .style import EXTRA_COLORS, INPUT_COLORS, fig_ax

__all__ = ["plot_budget"]


def _input_color(name: str, i: int) -> str:
    return INPUT_COLORS.get(name, EXTRA_COLORS[i % len(EXTRA_COLORS)])


def plot_budget(table: pd.DataFrame, *, ax: Axes | None = None,
                group: str | Sequence[str] | None = None) -> Figure:
    """Uncertainty budget: each input's share of the variance of ln E [%].

    Parameters
    ----------
    table
        Columns ``input``, ``share_pct`` (and ``rel_sd_pct``): the ``budget.table`` of one fit,
        or ``budget.csv`` of a campaign with grouping columns.
    ax
        Axes to draw on.
    group
        Column(s) naming the groups (default: ``material`` and ``tip`` if present).  With
        groups, one horizontal bar per group stacked by input (shares add up to 100 %);
        without, one bar per input annotated with its relative sd.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if group is None:
        group = [c for c in ("material", "tip") if c in table.columns]
    elif isinstance(group, str):
        group = [group]
    inputs = list(dict.fromkeys(table["input"]))
    if not group:
        fig, ax = fig_ax(ax, (6.0, 0.45 * len(inputs) + 1.2))
        t = table.set_index("input").loc[inputs]
        y = np.arange(len(inputs))[::-1]
        colors = [_input_color(n, i) for i, n in enumerate(inputs)]
        ax.barh(y, t["share_pct"], color=colors, height=0.6)
        for yi, (share, sd) in zip(y, zip(t["share_pct"], t.get("rel_sd_pct",
                                                                  [np.nan] * len(t)),
                                          strict=True), strict=True):
            txt = f"{share:.1f} %" + (f"  (sd {sd:.2g} % of E)" if np.isfinite(sd) else "")
            ax.text(share + 1.0, yi, txt, va="center", fontsize="x-small")
        ax.set_yticks(y, inputs)
        ax.set_xlim(0, 125)
        ax.set_xticks(np.arange(0, 101, 20))
    else:
        tab = table.groupby([*group, "input"], sort=False)["share_pct"].mean().unstack("input")
        tab = tab.reindex(columns=inputs).fillna(0.0)
        labels = [" / ".join(map(str, k if isinstance(k, tuple) else (k,))) for k in tab.index]
        fig, ax = fig_ax(ax, (8.0, 0.35 * len(labels) + 1.6))
        y = np.arange(len(labels))[::-1]
        left = np.zeros(len(labels))
        for i, name in enumerate(inputs):
            v = tab[name].to_numpy()
            ax.barh(y, v, left=left, color=_input_color(name, i), height=0.65, label=name)
            left += v
        ax.set_yticks(y, labels, fontsize="small")
        ax.set_xlim(0, 100)
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="x-small",
                  frameon=False, title="input", title_fontsize="x-small")
    ax.set_xlabel("Share of the variance of ln E [%]")
    ax.set_title("Uncertainty budget", fontsize="medium")
    return fig
