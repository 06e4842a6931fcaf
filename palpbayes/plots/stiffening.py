"""Modulus vs rest time with the fitted stiffening law (:mod:`palpbayes.stiffening`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..intervals import LEVEL
from .style import KPA, METHOD_COLORS, METHOD_LABELS, fig_ax, level_label

__all__ = ["plot_stiffening"]


# Many parameters: each optional layer of the figure (intervals, fitted curve and band, truth, the
# rested level) is an array the caller may or may not have.
def plot_stiffening(
    rest_time: np.ndarray,
    E: np.ndarray,
    *,
    E_lo: np.ndarray | None = None,
    E_hi: np.ndarray | None = None,
    curve_t: np.ndarray | None = None,
    curve_median: np.ndarray | None = None,
    curve_lo: np.ndarray | None = None,
    curve_hi: np.ndarray | None = None,
    curve_label: str = "fitted law",
    truth: tuple[np.ndarray, np.ndarray] | None = None,
    rested: tuple[float, float, float] | None = None,
    fit: Any = None,
    ax: Axes | None = None,
    level: float = LEVEL,
    label: str = "Bayes per palpation",
) -> Figure:
    """Modulus vs rest time since the previous excitation, with the fitted stiffening law.

    Parameters
    ----------
    rest_time
        [s] Rest time of each palpation.
    E, E_lo, E_hi
        [Pa] Per-palpation estimate and interval.
    curve_t, curve_median, curve_lo, curve_hi
        [s], [Pa] The fitted law E(t) = c1·exp(c2·t) + c3·exp(c4·t) and its band.
    curve_label
        Legend label of the curve (e.g. ``"fitted E(t) = c0 + c1·exp(c2·t)"``).
    truth
        (t [s], E [Pa]) of the true law (simulations).
    rested
        (E, lo, hi) [Pa] of a fully rested specimen, drawn as a band.
    fit
        A :class:`palpbayes.stiffening.StiffeningResult`: its preferred law's median and
        ``level`` band (``fit.predict``) on 300 rest times from 0 to 1.05·max(t), unless
        ``curve_*`` are given, labelled with ``fit.law``.
    ax
        Axes to draw on.
    level
        Probability content of the intervals (for the legend).
    label
        Legend label of the points.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = fig_ax(ax, (6.0, 4.0))
    t = np.asarray(rest_time, dtype=float)
    e = np.asarray(E, dtype=float) * KPA
    c = METHOD_COLORS["bayes"]
    law = curve_label
    if fit is not None and curve_median is None:
        curve_t = np.linspace(0.0, 1.05 * float(np.nanmax(t)), 300)
        pred = fit.predict(curve_t, level=level)
        curve_median = pred["median_pa"].to_numpy()
        curve_lo, curve_hi = pred["lo_pa"].to_numpy(), pred["hi_pa"].to_numpy()
        law = f"fitted {fit.law}"
    if rested is not None:
        ax.axhspan(rested[1] * KPA, rested[2] * KPA, color="0.88", lw=0)
        ax.axhline(rested[0] * KPA, color=METHOD_COLORS["gt"], lw=1.0,
                   label="rested specimen")
    if curve_t is not None and curve_median is not None:
        ct = np.asarray(curve_t, dtype=float)
        if curve_lo is not None and curve_hi is not None:
            ax.fill_between(ct, np.asarray(curve_lo) * KPA, np.asarray(curve_hi) * KPA,
                            color=c, alpha=0.25, lw=0,
                            label=f"{level_label(level)} credible band of the law")
        ax.plot(ct, np.asarray(curve_median) * KPA, color=c, lw=1.4, label=law)
    if truth is not None:
        ax.plot(np.asarray(truth[0]), np.asarray(truth[1]) * KPA, "--",
                color=METHOD_COLORS["truth"], lw=1.2, label=METHOD_LABELS["truth"])
    if E_lo is not None and E_hi is not None:
        lo = e - np.asarray(E_lo, dtype=float) * KPA
        hi = np.asarray(E_hi, dtype=float) * KPA - e
        ax.errorbar(t, e, yerr=[lo, hi], fmt="o", ms=4, color=c, mfc="white", capsize=2,
                    label=f"{label} ({level_label(level)})")
    else:
        ax.plot(t, e, "o", ms=4, color=c, mfc="white", label=label)
    ax.set_xlabel("Rest time since the previous palpation, t [s]")
    ax.set_ylabel("Young's modulus, E [kPa]")
    ax.set_title("Stiffening after repeated palpation", fontsize="medium")
    ax.legend(loc="best", fontsize="x-small", frameon=False)
    return fig
