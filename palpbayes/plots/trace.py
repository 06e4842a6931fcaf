"""One trace's fit: force vs depth with the posterior-predictive band, and the residuals."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..intervals import LEVEL
from ..units import format_force
from .style import METHOD_COLORS, MM, MN, decorate, fig_ax, level_label, lsq_of, median

__all__ = ["plot_force_depth", "plot_residuals"]

_DEPTH_LABEL = "Depth below posterior-median surface, d [mm]"


def _title(result: Any) -> str:
    tid = getattr(result, "trace_id", "") or ""
    data = getattr(result, "data", None)
    tip = data.model.tip.describe() if data is not None else ""
    return f"{tid} ({tip})" if tid and tip else tid or tip


def _posterior_median_curve(result: Any, z: np.ndarray) -> np.ndarray:
    """Pointwise median of the posterior's mean force curves at heights ``z`` [N] (each draw
    with its own layer when the layer was sampled)."""
    return result.predictive(z, n_draws=200)["median_n"].to_numpy()


def _lsq_curve(lsq: Any, model: Any, z: np.ndarray) -> np.ndarray:
    return lsq.Estar * model.shape(lsq.z_surf - z)


def _binned_mean(x: np.ndarray, y: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    edges = np.linspace(x.min(), x.max(), bins + 1)
    idx = np.clip(np.digitize(x, edges) - 1, 0, bins - 1)
    count = np.bincount(idx, minlength=bins)
    total = np.bincount(idx, weights=y, minlength=bins)
    centre = 0.5 * (edges[1:] + edges[:-1])
    ok = count > 0
    return centre[ok], total[ok] / count[ok]


# ----------------------------------------------------------------------------- force-depth


def plot_force_depth(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = LEVEL,
    n_draws: int = 200,
    n_grid: int = 300,
    seed: int = 0,
    show_excluded: bool = True,
    inset: bool = True,
) -> Figure:
    """Force vs depth: the data, the posterior-predictive band and the least-squares curve.

    Depth is measured from the posterior-median surface height, d = median(z_surf) − z [mm];
    force in N.  Two bands are drawn: the central ``level`` credible band of the mean force
    curve (parameter uncertainty only) and the wider posterior-predictive band of new
    observations (with the fitted noise sigma).

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` (anything with ``idata``, ``data`` and
        ``predictive``).
    lsq
        A :class:`~palpbayes.lsq.LSQResult` of the same trace (default ``result.lsq``); its
        curve E*·s(z_s − z) is drawn dashed.  Pass ``False`` to leave it out.
    ax
        Axes to draw on (default: a new figure).
    level
        Probability content of the bands.
    n_draws
        Posterior draws used for the bands.
    n_grid
        Points of the curves.
    seed
        Seed of the draw selection and of the predictive noise.
    show_excluded
        Also show loading samples outside the fit window (e.g. the first 20 % of a flat-punch
        penetration) as open grey markers.
    inset
        Add a zoom on the contact onset (−4 % to +12 % of the maximum depth), where the
        surface uncertainty and the difference between the methods are visible.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = fig_ax(ax)
    data = result.data
    lsq = lsq_of(result, lsq)
    zs = median(result, "z_surf")
    zsrc = data.loading.z if getattr(data, "loading", None) is not None else data.z
    zg = np.linspace(float(zsrc.min()), float(zsrc.max()), n_grid)
    obs = result.predictive(zg, n_draws=n_draws, noise=True, level=level, seed=seed)
    mean = result.predictive(zg, n_draws=n_draws, noise=False, level=level, seed=seed)
    lsq_f = None if lsq is None else _lsq_curve(lsq, lsq.model, zg)
    excluded = None
    if show_excluded and getattr(data, "loading", None) is not None:
        lz, lf = data.loading.z, data.loading.force
        out = ~np.isin(lz, data.z)
        if out.any():
            excluded = (lz[out], lf[out])
    axes = [ax]
    if inset:
        dmax = float(zs - data.z.min())
        # upper left, above the flat approach and the start of the loading curve (which rises
        # to the upper right); the legend goes to the lower right, below the curve
        ins = ax.inset_axes([0.07, 0.5, 0.34, 0.36])
        axes.append(ins)
    for k, a in enumerate(axes):
        ms = 1.5 if k == 0 else 2.5
        if excluded is not None:
            a.plot((zs - excluded[0]) * MM, excluded[1], "o", ms=ms + 0.5, mfc="none",
                   mew=0.4, color=METHOD_COLORS["data"], alpha=0.5, rasterized=True,
                   label="not fitted (outside window)")
        a.plot((zs - data.z) * MM, data.force, ".", ms=ms, color=METHOD_COLORS["data"],
               alpha=0.5, rasterized=True, label=f"data (n = {data.n_points})")
        dg = (zs - zg) * MM
        c = METHOD_COLORS["bayes"]
        a.fill_between(dg, obs["lo_n"], obs["hi_n"], color=c, alpha=0.15, lw=0,
                       label=f"Bayes {level_label(level)} predictive (new data)")
        a.fill_between(dg, mean["lo_n"], mean["hi_n"], color=c, alpha=0.45, lw=0,
                       label=f"Bayes {level_label(level)} credible band (mean)")
        a.plot(dg, mean["median_n"], color=c, lw=1.2, label="Bayes posterior median")
        if lsq_f is not None:
            a.plot(dg, lsq_f, "--", color=METHOD_COLORS["lsq"], lw=1.2, label="least squares")
        a.axvline(0.0, color="0.5", lw=0.6, ls=":")
    if inset:
        lo_d, hi_d = -0.04 * dmax, 0.12 * dmax
        ins.set_xlim(lo_d * MM, hi_d * MM)
        sel = (dg >= lo_d * MM) & (dg <= hi_d * MM)
        ylo = min(float(obs["lo_n"][sel].min()), -2 * data.f_unc)
        yhi = max(float(obs["hi_n"][sel].max()), 2 * data.f_unc)
        ins.set_ylim(ylo, yhi)
        ins.tick_params(labelsize="x-small")
        ins.set_title("near the surface", fontsize="x-small")
        ax.indicate_inset_zoom(ins, edgecolor="0.4")
    decorate(ax, _DEPTH_LABEL, "Force, F [N]", _title(result), "lower right")
    return fig


def plot_residuals(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    bins: int = 40,
) -> Figure:
    """Residuals (data − fitted curve) vs depth for Bayes and least squares.

    The Bayesian curve uses the posterior-median parameters (including the force offset F0);
    the least-squares curve is the paper's model without offset.  Points are the Bayesian
    residuals; lines are binned means of both methods (structure in them means the contact law
    does not fit); the grey band is ±2 sigma (posterior-median noise sd).  The axis holds them
    all (the least squares of an untared sensor miss by its offset).

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult`.
    lsq
        The least-squares result (default ``result.lsq``; ``False`` to leave it out).
    ax
        Axes to draw on.
    bins
        Depth bins of the running means.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = fig_ax(ax)
    data = result.data
    lsq = lsq_of(result, lsq)
    zs = median(result, "z_surf")
    depth = (zs - data.z) * MM
    sigma = median(result, "sigma")
    rb = (data.force - _posterior_median_curve(result, data.z)) * MN
    ax.axhspan(-2 * sigma * MN, 2 * sigma * MN, color="0.85", lw=0,
               label=f"±2 sigma (sigma = {format_force(sigma)})")
    ax.plot(depth, rb, ".", ms=1.5, color=METHOD_COLORS["bayes"], alpha=0.3, rasterized=True,
            label="Bayes residuals")
    x, m = _binned_mean(depth, rb, bins)
    ax.plot(x, m, color=METHOD_COLORS["bayes"], lw=1.4, label="Bayes, binned mean")
    shown = [rb]
    if lsq is not None:
        rl = (data.force - _lsq_curve(lsq, lsq.model, data.z)) * MN
        x, m = _binned_mean(depth, rl, bins)
        ax.plot(x, m, "--", color=METHOD_COLORS["lsq"], lw=1.4,
                label="least squares, binned mean")
        shown.append(m)  # an untared sensor's least squares can be off by far more
    ax.axhline(0.0, color="0.3", lw=0.6)
    # every residual drawn inside, and room for the legend below them: it must not hide any
    lo = min(min(float(np.min(v)) for v in shown), -2 * sigma * MN)
    hi = max(max(float(np.max(v)) for v in shown), 2 * sigma * MN)
    span = hi - lo if hi > lo else 1.0
    ax.set_ylim(lo - 0.42 * span, hi + 0.05 * span)
    decorate(ax, _DEPTH_LABEL, "Residual, F − F_fit [mN]", "Residuals", "lower left", ncol=2,
              borderaxespad=0.3)
    return fig
