"""Viscoelastic fits: force against time with the fit's band, the relaxation modulus E*(t)
with its band, and the approach/retract hysteresis of a record.

The fits are :class:`~palpbayes.rheology.RheologyFit` results (:func:`palpbayes.rheology.
fit_rheology`) or the same fits read back from a results folder,
:class:`~palpbayes.rheology.StoredRheologyFit` (:func:`palpbayes.rheology.load_rheology_fit`):
both give the block means (``data.time``, ``data.z``, ``data.force``, ``data.segment``), model
force curves at them (``force_curves(n)``; a stored fit also its stored band) and E*(t) with its
band (``relaxation(times, level)``; a stored fit has it on its stored times, the default here).
The record is an :class:`~palpbayes.trace.IndentationTrace` with segments, or a fit (its record).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter

from ..intervals import LEVEL, central_band
from ..rheology.store import StoredRheologyFit, relaxation_grid
from ..trace import SEGMENTS, IndentationTrace
from ..units import FORCE_PREFIXES, LENGTH_PREFIXES, PRESSURE_PREFIXES, si_scale
from .style import decorate, fig_ax, level_label

__all__ = ["plot_cycle_fit", "plot_relaxation", "plot_hysteresis", "RHEOLOGY_COLORS",
           "SEGMENT_COLORS"]

#: Colour per relaxation model (Okabe-Ito).
RHEOLOGY_COLORS: dict[str, str] = {"power-law": "#0072B2", "sls": "#D55E00",
                                   "pooled": "#009E73"}
#: Colour per segment of the cycle.
SEGMENT_COLORS: dict[str, str] = {"approach": "#56B4E9", "hold": "#E69F00",
                                  "retract": "#CC79A7"}
_LABELS = {"power-law": "power law", "sls": "SLS", "pooled": "pooled"}


def plot_cycle_fit(fit: Any, ax: Axes | None = None, *, level: float = LEVEL,
                   n_draws: int = 200, title: str | None = None) -> Figure:
    """Force against time [s]: the fitted block means, the fit's median force and its
    central ``level`` band over ``n_draws`` posterior draws, the segments shaded; the force in
    the SI unit that suits it (mN for a robot, nN for an AFM).

    Parameters
    ----------
    fit
        A :class:`~palpbayes.rheology.RheologyFit` or a
        :class:`~palpbayes.rheology.StoredRheologyFit`.
    ax
        Axes to draw on (default a new figure).
    level
        Central probability of the band.
    n_draws
        Posterior draws behind the band (a stored fit: its stored band, whatever ``n_draws``).
    title
        Default: the trace id, the model and whether its check passed.
    """
    fig, ax = fig_ax(ax, (7.0, 4.0))
    d = fit.data
    if isinstance(fit, StoredRheologyFit):
        lo, med, hi = fit.band(level)
    else:
        lo, med, hi = central_band(fit.force_curves(n_draws), level, axis=0)
    color = RHEOLOGY_COLORS.get(fit.rheology, "#0072B2")
    k, unit = si_scale(np.max(np.abs(d.force)), "N", FORCE_PREFIXES)
    for code, name in enumerate(SEGMENTS):
        t = d.time[d.segment == code]
        if t.size:
            ax.axvspan(t[0], t[-1], color=SEGMENT_COLORS[name], alpha=0.12, lw=0, label=name)
    ax.plot(d.time, d.force * k, ".", ms=2, color="0.35", label="data (block means)",
            rasterized=True)
    ax.fill_between(d.time, lo * k, hi * k, color=color, alpha=0.35, lw=0,
                    label=f"{_LABELS.get(fit.rheology, fit.rheology)}, {level_label(level)} band")
    ax.plot(d.time, med * k, color=color, lw=1.2, label="posterior median")
    if title is None:
        tid = _trace_id(fit)
        title = (f"{tid}: {_LABELS.get(fit.rheology, fit.rheology)} fit, model check "
                 f"{'passed' if fit.model_ok else 'FAILED'}")
    decorate(ax, "Time from the first fitted sample, t [s]", f"Force, F [{unit}]", title,
              "best")
    return fig


def plot_relaxation(fits: Any, ax: Axes | None = None, *, times=None, level: float = LEVEL,
                    truth=None, title: str = "Relaxation modulus") -> Figure:
    """E*(t) on log-log axes (Pa, kPa or MPa as suits it): median and central ``level``
    band of each fit.

    Parameters
    ----------
    fits
        A :class:`~palpbayes.rheology.RheologyFit` or
        :class:`~palpbayes.rheology.StoredRheologyFit`, or a mapping label -> fit.
    ax
        Axes to draw on (default a new figure).
    times
        [s] Times to draw at; default 60 log-spaced times over the recorded time scales of the
        first fit (its shortest step to its duration: :func:`~palpbayes.rheology.
        relaxation_grid`, the times a stored fit keeps its band at; a stored fit is
        interpolated between its stored times at others, and not drawn outside them).
    level
        Central probability of the bands.
    truth
        Optional callable t [s] -> E*(t) [Pa] (a simulated material's kernel), drawn dashed.
    title
        Axes title.
    """
    fig, ax = fig_ax(ax)
    if not isinstance(fits, Mapping):
        fits = {_LABELS.get(fits.rheology, fits.rheology): fits}
    first = next(iter(fits.values()))
    if times is None:
        times = relaxation_grid(first.data)
    times = np.asarray(times, dtype=float)
    tables = {label: fit.relaxation(times, level) for label, fit in fits.items()}
    k, unit = si_scale(max(float(t["E_star_hi_pa"].max()) for t in tables.values()), "Pa",
                       PRESSURE_PREFIXES)
    for i, (label, fit) in enumerate(fits.items()):
        tab = tables[label]
        color = RHEOLOGY_COLORS.get(fit.rheology, None) if len(fits) <= 2 else f"C{i}"
        ax.fill_between(times, tab["E_star_lo_pa"] * k, tab["E_star_hi_pa"] * k,
                        color=color, alpha=0.3, lw=0)
        ax.plot(times, tab["E_star_pa"] * k, color=color, lw=1.2,
                label=f"{label} ({level_label(level)} band)")
    if truth is not None:
        ax.plot(times, np.asarray(truth(times), dtype=float) * k, "k--", lw=1.0,
                label="true E*(t)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain = FuncFormatter(lambda v, _: f"{v:g}")  # 60, 70, 100 rather than 6 × 10^1
    ax.yaxis.set_major_formatter(plain)
    ax.yaxis.set_minor_formatter(plain)
    decorate(ax, "Time since a step strain, t [s]", f"Relaxation modulus, E*(t) [{unit}]",
              title, "best")
    return fig


def plot_hysteresis(trace: Any, ax: Axes | None = None, *, z_surf: float | None = None,
                    title: str | None = None) -> Figure:
    """Force against depth (or tip height when ``z_surf`` is None), one colour per segment,
    each in the SI unit that suits it: a retract below the approach is the hysteresis of a
    viscoelastic material.

    Parameters
    ----------
    trace
        An :class:`~palpbayes.trace.IndentationTrace` (segments from the motion when it does
        not record them); or a fit: a :class:`~palpbayes.rheology.StoredRheologyFit` draws its
        stored record (every segment), a :class:`~palpbayes.rheology.RheologyFit` the samples
        of its fitted segments, both against the depth below the fit's median surface.
    ax
        Axes to draw on (default a new figure).
    z_surf
        [m] Surface height (e.g. a fit's median) for the depth axis; default for a fit its
        posterior median, for a trace None (the tip height is drawn).
    title
        Default the trace id.
    """
    from ..io.motion_segments import cycle_segments

    fig, ax = fig_ax(ax)
    if isinstance(trace, StoredRheologyFit):
        z_surf = trace.z_surf if z_surf is None else z_surf
        trace = trace.record
        seg = np.asarray(trace.segment)
    else:
        if not isinstance(trace, IndentationTrace) and hasattr(trace, "data"):  # a RheologyFit
            z_surf = float(np.median(trace.draws["z_surf"])) if z_surf is None else z_surf
            trace = trace.data.trace
        seg = cycle_segments(trace)
    x = trace.z if z_surf is None else z_surf - trace.z
    kx, ux = si_scale(np.max(np.abs(x)), "m", LENGTH_PREFIXES)
    kf, uf = si_scale(np.max(np.abs(trace.force)), "N", FORCE_PREFIXES)
    x = x * kx
    for code, name in enumerate(SEGMENTS):
        sel = seg == code
        if sel.any():
            ax.plot(x[sel], trace.force[sel] * kf, ".", ms=1.5, color=SEGMENT_COLORS[name],
                    label=name, rasterized=True)
    xlabel = (f"Tip height, z [{ux}]" if z_surf is None
              else f"Depth below the fitted surface, d [{ux}]")
    decorate(ax, xlabel, f"Force, F [{uf}]",
              trace.trace_id if title is None else title, "best", markerscale=4)
    return fig


def _trace_id(fit: Any) -> str:
    """The trace id of a stored fit, or of the record behind a fit."""
    if isinstance(fit, StoredRheologyFit):
        return fit.trace_id
    return getattr(getattr(fit.data, "trace", None), "trace_id", "")
