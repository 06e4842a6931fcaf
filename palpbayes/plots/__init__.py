"""Figures for papers and reports (matplotlib only here; DESIGN §4).

Every function draws with matplotlib's object API on an optional ``ax`` (or ``fig``) and returns
the :class:`~matplotlib.figure.Figure`.  Without ``ax`` a new figure is made with
:class:`matplotlib.figure.Figure` directly, not through ``pyplot``: no global state, nothing to
close, any backend.  Nothing here calls ``matplotlib.use``; the caller chooses the backend (in
Jupyter, ``%matplotlib inline`` and ``display(fig)`` or a figure as the cell's last value).

Units on the axes: depth in mm, force in N, moduli in kPa, surface height relative to its
posterior median in µm (the posterior spread of z_surf is a few µm; mm would show only zeros).
Colours per method are fixed (Okabe-Ito, colour-blind safe): :data:`METHOD_COLORS`.  Dense data
points are rasterized so a PDF page stays small.

Functions
---------
:func:`plot_force_depth`     data, posterior-predictive band and least-squares curve
:func:`plot_residuals`       residuals vs depth, both methods, binned means and ±2 sigma
:func:`plot_posterior_E`     marginal posterior of E (statistical and with the budget)
:func:`plot_posterior_zsurf` marginal posterior of the surface height
:func:`plot_pair`            joint posterior of E and z_surf with the least-squares ellipse
:func:`plot_posterior`       the three above side by side
:func:`plot_walkers`         trace plots of the sampled parameters, one line per walker
:func:`plot_budget`          share of the variance of ln E per input of the budget
:func:`plot_comparison`      ground truth vs least squares vs Bayes per material × tip
:func:`plot_forest`          per-trace intervals of one material × tip with the pooled result
:func:`plot_stiffening`      modulus vs rest time with the fitted stiffening law and its band
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..results import MATERIAL_ORDER, TIP_ORDER, ordered

__all__ = [
    "METHOD_COLORS",
    "METHOD_LABELS",
    "INPUT_COLORS",
    "plot_force_depth",
    "plot_residuals",
    "plot_posterior_E",
    "plot_posterior_zsurf",
    "plot_pair",
    "plot_posterior",
    "plot_walkers",
    "plot_budget",
    "plot_comparison",
    "plot_forest",
    "plot_stiffening",
]

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
_EXTRA_COLORS = ["#F0E442", "#D55E00", "#999999", "#000000"]

_KPA = 1e-3
_MM = 1e3
_UM = 1e6
_MN = 1e3


# ----------------------------------------------------------------------------- helpers


def _fig_ax(ax: Axes | None, figsize: tuple[float, float] = (6.0, 4.0)) -> tuple[Figure, Axes]:
    """The figure of ``ax``, or a new constrained-layout figure with one axes."""
    if ax is not None:
        return ax.figure, ax
    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.add_subplot()


def _level_label(level: float) -> str:
    return f"{100 * level:g} %"


def _central(x: np.ndarray, level: float) -> tuple[float, float]:
    a = (1 - level) / 2
    lo, hi = np.quantile(x, [a, 1 - a])
    return float(lo), float(hi)


def _draws(result: Any, name: str) -> np.ndarray:
    """Flattened posterior draws of ``name`` from a BayesResult or an InferenceData."""
    idata = getattr(result, "idata", result)
    return np.asarray(idata.posterior[name]).ravel()


def _attrs(result: Any) -> dict:
    """Fit attributes (trace_id, burn, thin, model, ...) wherever arviz put them.

    In memory ``az.from_dict(attrs=...)`` keeps them on the InferenceData; after a netCDF round
    trip they sit on the groups (observed_data, constant_data).
    """
    idata = getattr(result, "idata", result)
    out: dict = {}
    for group in ("constant_data", "observed_data", "sample_stats", "posterior"):
        ds = getattr(idata, group, None) if hasattr(idata, group) else None
        if ds is not None:
            out.update({k: v for k, v in dict(getattr(ds, "attrs", {})).items()
                        if k not in out})
    out.update(dict(getattr(idata, "attrs", {}) or {}))
    return out


def _title(result: Any) -> str:
    tid = getattr(result, "trace_id", "") or ""
    data = getattr(result, "data", None)
    tip = data.model.tip.describe() if data is not None else ""
    return f"{tid} ({tip})" if tid and tip else tid or tip


def _posterior_median_curve(result: Any, z: np.ndarray) -> np.ndarray:
    """Force of the posterior-median parameters at heights ``z`` [N] (E*·s(d) + F0)."""
    es = float(np.median(_draws(result, "E_star")))
    zs = float(np.median(_draws(result, "z_surf")))
    f0 = float(np.median(_draws(result, "F0")))
    return es * result.data.shape(zs - z) + f0


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
    level: float = 0.9,
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
    fig, ax = _fig_ax(ax)
    data = result.data
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    zs = float(np.median(_draws(result, "z_surf")))
    zsrc = data.loading.z if getattr(data, "loading", None) is not None else data.z
    zg = np.linspace(float(zsrc.min()), float(zsrc.max()), n_grid)
    obs = result.predictive(zg, n_draws=n_draws, noise=True, level=level, seed=seed)
    mean = result.predictive(zg, n_draws=n_draws, noise=False, level=level, seed=seed)
    lsq_f = None if lsq is None or lsq is False else _lsq_curve(lsq, data.model, zg)
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
            a.plot((zs - excluded[0]) * _MM, excluded[1], "o", ms=ms + 0.5, mfc="none",
                   mew=0.4, color=METHOD_COLORS["data"], alpha=0.5, rasterized=True,
                   label="not fitted (outside window)")
        a.plot((zs - data.z) * _MM, data.force, ".", ms=ms, color=METHOD_COLORS["data"],
               alpha=0.5, rasterized=True, label=f"data (n = {data.n_points})")
        dg = (zs - zg) * _MM
        c = METHOD_COLORS["bayes"]
        a.fill_between(dg, obs["lo_n"], obs["hi_n"], color=c, alpha=0.15, lw=0,
                       label=f"Bayes {_level_label(level)} predictive (new data)")
        a.fill_between(dg, mean["lo_n"], mean["hi_n"], color=c, alpha=0.45, lw=0,
                       label=f"Bayes {_level_label(level)} credible band (mean)")
        a.plot(dg, mean["median_n"], color=c, lw=1.2, label="Bayes posterior median")
        if lsq_f is not None:
            a.plot(dg, lsq_f, "--", color=METHOD_COLORS["lsq"], lw=1.2, label="least squares")
        a.axvline(0.0, color="0.5", lw=0.6, ls=":")
    if inset:
        lo_d, hi_d = -0.04 * dmax, 0.12 * dmax
        ins.set_xlim(lo_d * _MM, hi_d * _MM)
        sel = (dg >= lo_d * _MM) & (dg <= hi_d * _MM)
        ylo = min(float(obs["lo_n"][sel].min()), -2 * data.f_unc)
        yhi = max(float(obs["hi_n"][sel].max()), 2 * data.f_unc)
        ins.set_ylim(ylo, yhi)
        ins.tick_params(labelsize="x-small")
        ins.set_title("near the surface", fontsize="x-small")
        ax.indicate_inset_zoom(ins, edgecolor="0.4")
    ax.set_xlabel("Depth below posterior-median surface, d [mm]")
    ax.set_ylabel("Force, F [N]")
    ax.set_title(_title(result), fontsize="medium")
    ax.legend(loc="lower right", fontsize="x-small", frameon=False)
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
    does not fit); the grey band is ±2 sigma (posterior-median noise sd).

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
    fig, ax = _fig_ax(ax)
    data = result.data
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    zs = float(np.median(_draws(result, "z_surf")))
    depth = (zs - data.z) * _MM
    sigma = float(np.median(_draws(result, "sigma")))
    rb = (data.force - _posterior_median_curve(result, data.z)) * _MN
    ax.axhspan(-2 * sigma * _MN, 2 * sigma * _MN, color="0.85", lw=0,
               label=f"±2 sigma (sigma = {sigma * _MN:.3g} mN)")
    ax.plot(depth, rb, ".", ms=1.5, color=METHOD_COLORS["bayes"], alpha=0.3, rasterized=True,
            label="Bayes residuals")
    x, m = _binned_mean(depth, rb, bins)
    ax.plot(x, m, color=METHOD_COLORS["bayes"], lw=1.4, label="Bayes, binned mean")
    if lsq is not None and lsq is not False:
        rl = (data.force - _lsq_curve(lsq, data.model, data.z)) * _MN
        x, m = _binned_mean(depth, rl, bins)
        ax.plot(x, m, "--", color=METHOD_COLORS["lsq"], lw=1.4,
                label="least squares, binned mean")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel("Depth below posterior-median surface, d [mm]")
    ax.set_ylabel("Residual, F − F_fit [mN]")
    ax.set_title("Residuals", fontsize="medium")
    # room for the legend below the points: it must not hide residuals
    lo = min(float(np.min(rb)), -2 * sigma * _MN)
    hi = max(float(np.max(rb)), 2 * sigma * _MN)
    span = hi - lo if hi > lo else 1.0
    ax.set_ylim(lo - 0.42 * span, hi + 0.05 * span)
    ax.legend(loc="lower left", fontsize="x-small", frameon=False, ncol=2,
              borderaxespad=0.3)
    return fig


# ----------------------------------------------------------------------------- posterior


def _hist(ax: Axes, x: np.ndarray, color: str, label: str, filled: bool, bins: int,
          peak: bool = False) -> None:
    """Histogram as a density, or scaled to a peak of 1 when ``peak`` (very unequal widths)."""
    dens, edges = np.histogram(x, bins=bins, density=True)
    if peak and dens.max() > 0:
        dens = dens / dens.max()
    if filled:
        ax.stairs(dens, edges, fill=True, color=color, alpha=0.35, label=label)
    else:
        ax.stairs(dens, edges, color=color, lw=1.2, label=label)


def plot_posterior_E(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = 0.9,
    bins: int = 60,
    truth: float | None = None,
) -> Figure:
    """Marginal posterior of Young's modulus E [kPa].

    Two histograms, each scaled to a peak of 1 (their widths can differ a hundredfold):
    ``E`` at the model's Poisson ratio (statistical uncertainty of the trace only) and
    ``E_total`` with the uncertainty budget (Poisson ratio, tip radius, force gain,
    compliance).  Medians and central ``level`` intervals are marked; the
    least-squares estimate with its own interval is drawn as an error bar above.

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` or an arviz ``InferenceData``.
    lsq
        Least-squares result (default ``result.lsq``; ``False`` to leave it out).
    ax
        Axes to draw on.
    level
        Probability content of the marked intervals.
    bins
        Histogram bins.
    truth
        [Pa] A known true value to mark (simulations).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _fig_ax(ax, (5.0, 3.6))
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    c = METHOD_COLORS["bayes"]
    e_tot = _draws(result, "E_total") * _KPA
    e_stat = _draws(result, "E") * _KPA
    _hist(ax, e_tot, c, "E with budget", True, bins, peak=True)
    # the trace-only posterior is often 100x narrower: its own bins, scaled to the same peak
    _hist(ax, e_stat, c, "E, trace only (fixed nu)", False, bins, peak=True)
    lo, hi = _central(e_tot, level)
    med = float(np.median(e_tot))
    ax.axvline(med, color=c, lw=1.2)
    ax.axvspan(lo, hi, color=c, alpha=0.08, lw=0)
    if lsq is not None and lsq is not False:
        ax.errorbar([lsq.E * _KPA], [1.1],
                    xerr=[[(lsq.E - lsq.E_lo) * _KPA], [(lsq.E_hi - lsq.E) * _KPA]],
                    fmt="s", ms=4, color=METHOD_COLORS["lsq"], capsize=3,
                    label=f"least squares ± {_level_label(getattr(lsq, 'level', level))}")
    if truth is not None:
        ax.axvline(truth * _KPA, color=METHOD_COLORS["truth"], ls="--", lw=1.2,
                   label=METHOD_LABELS["truth"])
    ax.set_ylim(0, 1.45)
    ax.set_xlabel("Young's modulus, E [kPa]")
    ax.set_ylabel("Posterior density (peak = 1)")
    ax.set_title(f"E = {med:.1f} kPa, {_level_label(level)} interval [{lo:.1f}, {hi:.1f}]",
                 fontsize="medium")
    ax.legend(loc="upper left", fontsize="x-small", frameon=False)
    return fig


def plot_posterior_zsurf(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = 0.9,
    bins: int = 60,
    truth: float | None = None,
) -> Figure:
    """Marginal posterior of the surface height, relative to its median [µm].

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` or an arviz ``InferenceData``.
    lsq
        Least-squares result (default ``result.lsq``); its z_surf ± interval is marked.
    ax
        Axes to draw on.
    level
        Probability content of the marked interval.
    bins
        Histogram bins.
    truth
        [m] A known true surface height to mark.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _fig_ax(ax, (5.0, 3.6))
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    z = _draws(result, "z_surf")
    zm = float(np.median(z))
    rel = (z - zm) * _UM
    c = METHOD_COLORS["bayes"]
    _hist(ax, rel, c, "Bayes posterior", True, bins)
    lo, hi = _central(rel, level)
    ax.axvline(0.0, color=c, lw=1.2)
    ax.axvspan(lo, hi, color=c, alpha=0.08, lw=0)
    top = ax.get_ylim()[1]
    if lsq is not None and lsq is not False:
        from scipy import stats

        n = getattr(lsq, "n_points", 1000)
        t = stats.t.ppf(0.5 + level / 2, max(n - 2, 1))
        ax.errorbar([(lsq.z_surf - zm) * _UM], [1.12 * top],
                    xerr=[[t * lsq.z_surf_sd * _UM], [t * lsq.z_surf_sd * _UM]], fmt="s", ms=4,
                    color=METHOD_COLORS["lsq"], capsize=3,
                    label=f"least squares ± {_level_label(level)}")
    if truth is not None:
        ax.axvline((truth - zm) * _UM, color=METHOD_COLORS["truth"], ls="--", lw=1.2,
                   label=METHOD_LABELS["truth"])
    ax.set_ylim(0, top * 1.4)
    ax.set_xlabel(f"z_surf − {zm * _MM:.3f} mm (posterior median) [µm]")
    ax.set_ylabel("Posterior density [1/µm]")
    ax.set_title(f"z_surf: {_level_label(level)} interval [{lo:+.1f}, {hi:+.1f}] µm",
                 fontsize="medium")
    ax.legend(loc="upper left", fontsize="x-small", frameon=False)
    return fig


def plot_pair(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = 0.9,
    max_points: int = 3000,
    seed: int = 0,
) -> Figure:
    """Joint posterior of E (trace only, fixed nu) [kPa] and z_surf − median [µm].

    The surface height and the modulus are strongly correlated (a higher surface means deeper
    indentation, hence a softer material), which is why the surface uncertainty dominates the
    statistical part of the budget (DESIGN §8).  Draws are a random subset, rasterized; the
    least-squares estimate is drawn with its Gauss-Newton ``level`` confidence ellipse.

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` or an arviz ``InferenceData``.
    lsq
        Least-squares result (default ``result.lsq``; ``False`` to leave it out).
    ax
        Axes to draw on.
    level
        Probability content of the ellipse.
    max_points
        Draws plotted at most.
    seed
        Seed of the subset.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _fig_ax(ax, (5.0, 3.6))
    if lsq is None:
        lsq = getattr(result, "lsq", None)
    e = _draws(result, "E") * _KPA
    z = _draws(result, "z_surf")
    zm = float(np.median(z))
    rel = (z - zm) * _UM
    rng = np.random.default_rng(seed)
    idx = rng.choice(e.size, size=min(max_points, e.size), replace=False)
    c = METHOD_COLORS["bayes"]
    ax.plot(rel[idx], e[idx], ".", ms=2, alpha=0.35, color=c, rasterized=True,
            label="Bayes posterior draws")
    r = np.corrcoef(rel, e)[0, 1] if e.std() > 0 and rel.std() > 0 else np.nan
    if lsq is not None and lsq is not False and np.all(np.isfinite(lsq.cov)):
        from scipy import stats

        scale = 1.0 - lsq.model.nu ** 2
        # cov of (E* [Pa], z_s [m]) -> (E [kPa], z [µm])
        J = np.diag([scale * _KPA, _UM])
        cov = J @ np.asarray(lsq.cov) @ J
        k = np.sqrt(stats.chi2.ppf(level, 2))
        # ellipse in (x = z, y = E): mean + k·L·(cos, sin) with L the Cholesky factor
        covxy = cov[::-1, ::-1]
        w, v = np.linalg.eigh(covxy)
        L = v @ np.diag(np.sqrt(np.clip(w, 0.0, None)))
        th = np.linspace(0.0, 2.0 * np.pi, 181)
        pts = k * L @ np.vstack([np.cos(th), np.sin(th)])
        ax.plot((lsq.z_surf - zm) * _UM + pts[0], lsq.E * _KPA + pts[1],
                color=METHOD_COLORS["lsq"], lw=1.2)
        ax.plot([(lsq.z_surf - zm) * _UM], [lsq.E * _KPA], "s", ms=4,
                color=METHOD_COLORS["lsq"],
                label=f"least squares, {_level_label(level)} ellipse")
    ax.set_xlabel(f"z_surf − {zm * _MM:.3f} mm (posterior median) [µm]")
    ax.set_ylabel("E, trace only (fixed nu) [kPa]")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title(f"Joint posterior (correlation {r:+.2f})", fontsize="medium")
    ax.legend(loc="best", fontsize="x-small", frameon=False)
    return fig


def plot_posterior(result: Any, lsq: Any = None, *, fig: Figure | None = None,
                   level: float = 0.9, truth: Mapping[str, float] | None = None) -> Figure:
    """Marginal posteriors of E and z_surf and their joint posterior, side by side.

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult`.
    lsq
        Least-squares result (default ``result.lsq``).
    fig
        Figure to draw in (default: a new 12 × 3.6 in figure).
    level
        Probability content of intervals.
    truth
        Optional known values ``{"E": Pa, "z_surf": m}`` (simulations).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if fig is None:
        fig = Figure(figsize=(12.0, 3.6), layout="constrained")
    axes = fig.subplots(1, 3)
    truth = dict(truth or {})
    plot_posterior_E(result, lsq, ax=axes[0], level=level, truth=truth.get("E"))
    plot_posterior_zsurf(result, lsq, ax=axes[1], level=level, truth=truth.get("z_surf"))
    plot_pair(result, lsq, ax=axes[2], level=level)
    return fig


# ----------------------------------------------------------------------------- walkers

_WALKER_VARS: dict[str, tuple[str, float, str]] = {
    # name -> (label, scale, unit)
    "E_star": ("E*", _KPA, "kPa"),
    "z_surf": ("z_surf − median", _UM, "µm"),
    "sigma": ("sigma", _MN, "mN"),
    "F0": ("F0", _MN, "mN"),
    "phi": ("phi (AR(1))", 1.0, "-"),
    "nu_t": ("nu_t (Student-t)", 1.0, "-"),
}


def plot_walkers(result: Any, var_names: Sequence[str] | None = None, *,
                 fig: Figure | None = None, max_walkers: int = 64,
                 title: bool = True) -> Figure:
    """Trace plots: each sampled parameter vs sampler step, one thin line per walker.

    The stored chains are after burn-in and thinning (netCDF attributes ``burn`` and ``thin``);
    the x axis is the sampler step.  Well-mixed walkers overlap as a uniform band; a walker
    stuck apart or a drift is a convergence problem (R-hat, ESS in the title).

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` or an arviz ``InferenceData``.
    var_names
        Posterior variables (default: E_star, z_surf, sigma, F0 and phi / nu_t if present).
    fig
        Figure to draw in (default: a new figure, one row per variable).
    max_walkers
        Walkers drawn at most.
    title
        Add a title naming the trace and the number of walkers.

    Returns
    -------
    matplotlib.figure.Figure
    """
    idata = getattr(result, "idata", result)
    post = idata.posterior
    if var_names is None:
        var_names = [n for n in _WALKER_VARS if n in post]
    attrs = _attrs(result)
    burn = int(attrs.get("burn", 0))
    thin = int(attrs.get("thin", 1))
    diag = getattr(result, "diagnostics", None)
    if fig is None:
        fig = Figure(figsize=(8.0, 1.6 * len(var_names) + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(var_names), 1, sharex=True))
    for ax, name in zip(axes, var_names, strict=True):
        label, scale, unit = _WALKER_VARS.get(name, (name, 1.0, "-"))
        x = np.asarray(post[name])  # (chain = walker, draw)
        if name == "z_surf":
            x = x - np.median(x)
        x = x[:max_walkers] * scale
        steps = burn + thin * np.arange(x.shape[1])
        for w in x:
            ax.plot(steps, w, lw=0.3, alpha=0.5, color=METHOD_COLORS["bayes"], rasterized=True)
        ax.set_ylabel(f"{label} [{unit}]", fontsize="small")
        if diag is not None and name in getattr(diag, "rhat", {}):
            ax.set_title(f"{name}: R-hat {diag.rhat[name]:.4f}, ESS bulk "
                         f"{diag.ess_bulk[name]:.0f}, tail {diag.ess_tail[name]:.0f}",
                         fontsize="small", loc="left")
    axes[-1].set_xlabel(f"Sampler step (after burn-in {burn}, thinned by {thin})")
    tid = attrs.get("trace_id", getattr(result, "trace_id", ""))
    if title:
        fig.suptitle(f"Walkers{': ' + str(tid) if tid else ''} ({x.shape[0]} walkers)",
                     fontsize="medium")
    return fig


# ----------------------------------------------------------------------------- budget


def _input_color(name: str, i: int) -> str:
    return INPUT_COLORS.get(name, _EXTRA_COLORS[i % len(_EXTRA_COLORS)])


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
        fig, ax = _fig_ax(ax, (6.0, 0.45 * len(inputs) + 1.2))
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
        fig, ax = _fig_ax(ax, (8.0, 0.35 * len(labels) + 1.6))
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


# ----------------------------------------------------------------------------- comparison


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
    fig, ax = _fig_ax(ax, (10.0, 4.5))
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
            gt = float(sub["gt_E_pa"].dropna().iloc[0]) * _KPA
            sd = float(sub["gt_sd_pa"].dropna().iloc[0]) * _KPA if "gt_sd_pa" in sub and \
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
                    pe = float(row["paper_E_pa"].dropna().iloc[0]) * _KPA
                    ps = float(row["paper_sd_pa"].dropna().iloc[0]) * _KPA \
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
                e = r["E_pa"] * _KPA
                if show_new and "E_new_lo_pa" in r and np.isfinite(r["E_new_lo_pa"]):
                    ax.vlines(xm, r["E_new_lo_pa"] * _KPA, r["E_new_hi_pa"] * _KPA,
                              color=color, lw=1.0, zorder=2)
                    handles["new"] = (Line2D([], [], color="0.3", lw=1.0),
                                      "thin: 90 % interval for a new specimen")
                ax.vlines(xm, r["E_lo_pa"] * _KPA, r["E_hi_pa"] * _KPA, color=color, lw=3.0,
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
    fig, ax = _fig_ax(ax, (5.0, 0.4 * len(ids) + 1.8))
    n = len(ids)
    ypos = {tid: n + 1 - i for i, tid in enumerate(ids)}  # pooled rows at the bottom
    off = {m: (k - (len(methods) - 1) / 2) * 0.22 for k, m in enumerate(methods)}
    seen = set()
    if gt is not None and np.isfinite(gt[0]):
        g, s = gt[0] * _KPA, (gt[1] if np.isfinite(gt[1]) else 0.0) * _KPA
        ax.axvspan(g - s, g + s, color="0.88", lw=0, zorder=0)
        ax.axvline(g, color=METHOD_COLORS["gt"], lw=1.2, zorder=1,
                   label="Instron GT, mean ± sd")
    for _, r in summary.iterrows():
        m = r["method"]
        if m not in off:
            continue
        y = ypos[r["trace_id"]] + off[m]
        c = METHOD_COLORS.get(m, "k")
        ax.hlines(y, r["E_lo_pa"] * _KPA, r["E_hi_pa"] * _KPA, color=c, lw=2.0)
        lab = None if m in seen else f"{METHOD_LABELS.get(m, m)}, per trace"
        seen.add(m)
        ax.plot([r["E_pa"] * _KPA], [y], "o", ms=4, color=c, mec="white", mew=0.5, label=lab)
    labels = {v: k for k, v in ypos.items()}
    if pooled is not None:
        p = pd.Series(pooled)
        c = METHOD_COLORS["bayes"]
        ax.hlines(0.9, p["E_lo_pa"] * _KPA, p["E_hi_pa"] * _KPA, color=c, lw=3.0)
        ax.plot([p["E_pa"] * _KPA], [0.9], "D", ms=6, color=c, mec="white",
                label="pooled: material")
        labels[0.9] = "pooled mean"
        if "E_new_lo_pa" in p and np.isfinite(p["E_new_lo_pa"]):
            cn = METHOD_COLORS["pooled"]
            ax.hlines(0.2, p["E_new_lo_pa"] * _KPA, p["E_new_hi_pa"] * _KPA, color=cn, lw=3.0)
            ax.plot([p.get("E_new_pa", p["E_pa"]) * _KPA], [0.2], "D", ms=6, color=cn,
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


# ----------------------------------------------------------------------------- stiffening


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
    truth: tuple[np.ndarray, np.ndarray] | None = None,
    rested: tuple[float, float, float] | None = None,
    fit: Any = None,
    ax: Axes | None = None,
    level: float = 0.9,
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
    fig, ax = _fig_ax(ax, (6.0, 4.0))
    t = np.asarray(rest_time, dtype=float)
    e = np.asarray(E, dtype=float) * _KPA
    c = METHOD_COLORS["bayes"]
    law = "fitted law"
    if fit is not None and curve_median is None:
        curve_t = np.linspace(0.0, 1.05 * float(np.nanmax(t)), 300)
        pred = fit.predict(curve_t, level=level)
        curve_median = pred["median_pa"].to_numpy()
        curve_lo, curve_hi = pred["lo_pa"].to_numpy(), pred["hi_pa"].to_numpy()
        law = f"fitted {fit.law}"
    if rested is not None:
        ax.axhspan(rested[1] * _KPA, rested[2] * _KPA, color="0.88", lw=0)
        ax.axhline(rested[0] * _KPA, color=METHOD_COLORS["gt"], lw=1.0,
                   label="rested specimen")
    if curve_t is not None and curve_median is not None:
        ct = np.asarray(curve_t, dtype=float)
        if curve_lo is not None and curve_hi is not None:
            ax.fill_between(ct, np.asarray(curve_lo) * _KPA, np.asarray(curve_hi) * _KPA,
                            color=c, alpha=0.25, lw=0,
                            label=f"{_level_label(level)} credible band of the law")
        ax.plot(ct, np.asarray(curve_median) * _KPA, color=c, lw=1.4, label=law)
    if truth is not None:
        ax.plot(np.asarray(truth[0]), np.asarray(truth[1]) * _KPA, "--",
                color=METHOD_COLORS["truth"], lw=1.2, label=METHOD_LABELS["truth"])
    if E_lo is not None and E_hi is not None:
        lo = e - np.asarray(E_lo, dtype=float) * _KPA
        hi = np.asarray(E_hi, dtype=float) * _KPA - e
        ax.errorbar(t, e, yerr=[lo, hi], fmt="o", ms=4, color=c, mfc="white", capsize=2,
                    label=f"{label} ({_level_label(level)})")
    else:
        ax.plot(t, e, "o", ms=4, color=c, mfc="white", label=label)
    ax.set_xlabel("Rest time since the previous palpation, t [s]")
    ax.set_ylabel("Young's modulus, E [kPa]")
    ax.set_title("Stiffening after repeated palpation", fontsize="medium")
    ax.legend(loc="best", fontsize="x-small", frameon=False)
    return fig
