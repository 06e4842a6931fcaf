"""Posteriors of one trace: E, the surface height, and their joint distribution."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..contact import youngs_factor
from ..intervals import LEVEL, central, hull
from .style import (
    KPA,
    METHOD_COLORS,
    MM,
    UM,
    decorate,
    draws,
    fig_ax,
    level_label,
    lsq_errorbar,
    lsq_of,
    mark_interval,
    truth_line,
)

__all__ = ["plot_posterior_E", "plot_posterior_zsurf", "plot_pair", "plot_posterior"]


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


def _zsurf_relative(result: Any) -> tuple[float, np.ndarray]:
    """Posterior median of z_surf [m] and the draws relative to it [µm]."""
    z = draws(result, "z_surf")
    zm = float(np.median(z))
    return zm, (z - zm) * UM


def _zsurf_label(zm: float) -> str:
    """Axis label of surface heights relative to their posterior median ``zm`` [m]."""
    return f"z_surf − {zm * MM:.3f} mm (posterior median) [µm]"


def plot_posterior_E(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = LEVEL,
    bins: int = 60,
    truth: float | None = None,
) -> Figure:
    """Marginal posterior of Young's modulus E [kPa].

    Two histograms, each scaled to a peak of 1 (their widths can differ a hundredfold):
    ``E`` at the model's Poisson ratio (statistical uncertainty of the trace only) and
    ``E_total`` with the uncertainty budget (Poisson ratio, tip radius, force gain,
    compliance).  Medians and central ``level`` intervals are marked; the
    least-squares estimate with its own interval is drawn as an error bar above.  A fit with
    a material misfit also shades its full interval, the envelope over the model-form
    alternatives (:mod:`palpbayes.bayes.modelform`).

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
    fig, ax = fig_ax(ax, (5.0, 3.6))
    lsq = lsq_of(result, lsq)
    c = METHOD_COLORS["bayes"]
    e_tot = draws(result, "E_total") * KPA
    e_stat = draws(result, "E") * KPA
    _hist(ax, e_tot, c, "E with budget", True, bins, peak=True)
    # the trace-only posterior is often 100x narrower: its own bins, scaled to the same peak
    _hist(ax, e_stat, c, "E, trace only (fixed nu)", False, bins, peak=True)
    # the row's numbers (BayesResult.intervals): E at the stated inputs, the budget interval
    # widened to hold the statistical one; at another level, the draws' own
    intervals = getattr(result, "intervals", None)
    med = float(np.median(e_stat))
    if intervals is not None and level == LEVEL:
        lo, hi = (v * KPA for v in intervals()["budget"])
    else:
        lo, hi = hull(central(e_tot, level), central(e_stat, level))
    mark_interval(ax, med, lo, hi, c)
    if lsq is not None:
        lsq_errorbar(ax, lsq.E * KPA, 1.1, (lsq.E - lsq.E_lo) * KPA, (lsq.E_hi - lsq.E) * KPA,
                      f"least squares ± {level_label(getattr(lsq, 'level', level))}")
    if truth is not None:
        truth_line(ax, truth * KPA)
    title = f"E = {med:.1f} kPa, {level_label(level)} interval [{lo:.1f}, {hi:.1f}]"
    form = getattr(result, "model_form", None)
    if form is not None and np.isfinite(form.lo_pa) and np.isfinite(form.hi_pa):
        f_lo, f_hi = form.lo_pa * KPA, form.hi_pa * KPA
        ax.axvspan(f_lo, f_hi, color="0.88", zorder=0, lw=0,
                   label="with the model form (material misfit)")
        title += f",\nwith the model form [{f_lo:.1f}, {f_hi:.1f}]"
    ax.set_ylim(0, 1.45)
    decorate(ax, "Young's modulus, E [kPa]", "Posterior density (peak = 1)", title,
              "upper left")
    return fig


def plot_posterior_zsurf(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = LEVEL,
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
    fig, ax = fig_ax(ax, (5.0, 3.6))
    lsq = lsq_of(result, lsq)
    zm, rel = _zsurf_relative(result)
    c = METHOD_COLORS["bayes"]
    _hist(ax, rel, c, "Bayes posterior", True, bins)
    lo, hi = central(rel, level)
    mark_interval(ax, 0.0, lo, hi, c)
    top = ax.get_ylim()[1]
    if lsq is not None:
        from scipy import stats

        n = getattr(lsq, "n_points", 1000)
        t = stats.t.ppf(0.5 + level / 2, max(n - 2, 1))
        half = t * lsq.z_surf_sd * UM
        lsq_errorbar(ax, (lsq.z_surf - zm) * UM, 1.12 * top, half, half,
                      f"least squares ± {level_label(level)}")
    if truth is not None:
        truth_line(ax, (truth - zm) * UM)
    ax.set_ylim(0, top * 1.4)
    decorate(ax, _zsurf_label(zm), "Posterior density [1/µm]",
              f"z_surf: {level_label(level)} interval [{lo:+.1f}, {hi:+.1f}] µm", "upper left")
    return fig


def plot_pair(
    result: Any,
    lsq: Any = None,
    *,
    ax: Axes | None = None,
    level: float = LEVEL,
    max_points: int = 3000,
    seed: int = 0,
) -> Figure:
    """Joint posterior of E (trace only, fixed nu) [kPa] and z_surf − median [µm].

    The surface height and the modulus are strongly correlated (a higher surface means deeper
    indentation, hence a softer material), which is why the surface uncertainty dominates the
    statistical part of the budget (docs/design.md §8).  Draws are a random subset, rasterized; the
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
    fig, ax = fig_ax(ax, (5.0, 3.6))
    lsq = lsq_of(result, lsq)
    e = draws(result, "E") * KPA
    zm, rel = _zsurf_relative(result)
    rng = np.random.default_rng(seed)
    idx = rng.choice(e.size, size=min(max_points, e.size), replace=False)
    c = METHOD_COLORS["bayes"]
    ax.plot(rel[idx], e[idx], ".", ms=2, alpha=0.35, color=c, rasterized=True,
            label="Bayes posterior draws")
    r = np.corrcoef(rel, e)[0, 1] if e.std() > 0 and rel.std() > 0 else np.nan
    if lsq is not None and np.all(np.isfinite(lsq.cov)):
        from scipy import stats

        scale = youngs_factor(lsq.model.nu)
        # cov of (E* [Pa], z_s [m]) -> (E [kPa], z [µm])
        J = np.diag([scale * KPA, UM])
        cov = J @ np.asarray(lsq.cov) @ J
        k = np.sqrt(stats.chi2.ppf(level, 2))
        # ellipse in (x = z, y = E): mean + k·L·(cos, sin) with L the Cholesky factor
        covxy = cov[::-1, ::-1]
        w, v = np.linalg.eigh(covxy)
        L = v @ np.diag(np.sqrt(np.clip(w, 0.0, None)))
        th = np.linspace(0.0, 2.0 * np.pi, 181)
        pts = k * L @ np.vstack([np.cos(th), np.sin(th)])
        ax.plot((lsq.z_surf - zm) * UM + pts[0], lsq.E * KPA + pts[1],
                color=METHOD_COLORS["lsq"], lw=1.2)
        ax.plot([(lsq.z_surf - zm) * UM], [lsq.E * KPA], "s", ms=4,
                color=METHOD_COLORS["lsq"],
                label=f"least squares, {level_label(level)} ellipse")
    ax.ticklabel_format(axis="y", useOffset=False)
    decorate(ax, _zsurf_label(zm), "E, trace only (fixed nu) [kPa]",
              f"Joint posterior (correlation {r:+.2f})", "best")
    return fig


def plot_posterior(result: Any, lsq: Any = None, *, fig: Figure | None = None,
                   level: float = LEVEL, truth: Mapping[str, float] | None = None) -> Figure:
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
