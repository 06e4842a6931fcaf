"""Colours, units and small helpers shared by every figure of :mod:`palpbayes.plots`."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

__all__ = ["METHOD_COLORS", "METHOD_LABELS", "INPUT_COLORS", "EXTRA_COLORS", "KPA", "MM", "UM",
           "MN", "fig_ax", "level_label", "draws", "median", "lsq_of", "mark_interval",
           "lsq_errorbar", "truth_line", "decorate"]

#: One colour per method, used by every figure (Okabe-Ito palette).
METHOD_COLORS: dict[str, str] = {
    "data": "#7f7f7f",
    "gt": "#222222",
    "lsq": "#D55E00",      # vermillion
    "bayes": "#0072B2",    # blue
    "pooled": "#56B4E9",   # sky blue
    "paper": "#009E73",    # bluish green
    "truth": "#CC79A7",    # reddish purple
}
#: Legend labels of the methods.
METHOD_LABELS: dict[str, str] = {
    "data": "data",
    "gt": "Instron ground truth",
    "lsq": "least squares",
    "bayes": "Bayes",
    "pooled": "Bayes, pooled",
    "paper": "paper (robot)",
    "truth": "true value",
}
#: Colours of the inputs of the uncertainty budget.
INPUT_COLORS: dict[str, str] = {
    "E* (posterior)": "#0072B2",
    "mu (pooled posterior)": "#0072B2",
    "Poisson ratio": "#E69F00",
    "tip radius": "#009E73",
    "force gain": "#CC79A7",
    "compliance": "#56B4E9",
}
#: Colours cycled through for budget inputs that have none in :data:`INPUT_COLORS`.
EXTRA_COLORS = ["#F0E442", "#D55E00", "#999999", "#000000"]

#: Factors from SI to the units on the axes: Pa -> kPa, m -> mm, m -> µm, N -> mN.
KPA = 1e-3
MM = 1e3
UM = 1e6
MN = 1e3


def fig_ax(ax: Axes | None, figsize: tuple[float, float] = (6.0, 4.0)) -> tuple[Figure, Axes]:
    """The figure of ``ax``, or a new constrained-layout figure with one axes."""
    if ax is not None:
        return ax.figure, ax
    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.add_subplot()


def level_label(level: float) -> str:
    """A credible level as shown in labels: 0.9 -> '90 %'."""
    return f"{100 * level:g} %"


def draws(result: Any, name: str) -> np.ndarray:
    """Flattened posterior draws of ``name`` from a BayesResult or an InferenceData."""
    idata = getattr(result, "idata", result)
    return np.asarray(idata.posterior[name]).ravel()


def median(result: Any, name: str) -> float:
    """Posterior median of ``name`` (see :func:`draws`)."""
    return float(np.median(draws(result, name)))


def lsq_of(result: Any, lsq: Any) -> Any:
    """The least-squares result to draw: ``lsq``, else ``result.lsq``; None for ``lsq=False``."""
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    return None if lsq is False else lsq


def mark_interval(ax: Axes, centre: float, lo: float, hi: float, color: str) -> None:
    """A vertical line at ``centre`` over a light band from ``lo`` to ``hi``."""
    ax.axvline(centre, color=color, lw=1.2)
    ax.axvspan(lo, hi, color=color, alpha=0.08, lw=0)


def lsq_errorbar(ax: Axes, x: float, y: float, below: float, above: float, label: str) -> None:
    """The least-squares estimate at (x, y) with a horizontal error bar [x - below, x + above]."""
    ax.errorbar([x], [y], xerr=[[below], [above]], fmt="s", ms=4, color=METHOD_COLORS["lsq"],
                capsize=3, label=label)


def truth_line(ax: Axes, x: float) -> None:
    """A dashed vertical line at a known true value."""
    ax.axvline(x, color=METHOD_COLORS["truth"], ls="--", lw=1.2, label=METHOD_LABELS["truth"])


def decorate(ax: Axes, xlabel: str, ylabel: str, title: str, legend_loc: str,
              **legend_kw: Any) -> None:
    """Axis labels, a medium-size title and the small frameless legend of every figure."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize="medium")
    ax.legend(loc=legend_loc, fontsize="x-small", frameon=False, **legend_kw)
