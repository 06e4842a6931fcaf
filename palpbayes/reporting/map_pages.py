"""The figure and report pages of a stiffness map (``palpbayes map``).

``map.png``: mean, uncertainty, probability and profile in one figure.  ``map-report.pdf``
(A4 landscape): a summary page (the lump with its intervals, the background, the field's
hyperparameters, every flag), the heat map beside the naive least-squares map, the
uncertainty map, the probability map, the profile through the lump and the methods.
"""

from __future__ import annotations

import datetime as _dt
import os
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .. import __version__
from ..io.atomic import write_with
from ..maps.run import MapResult
from ..plots.maps import plot_map, plot_map_panel, plot_profile
from ..units import format_length, format_pressure
from .format import wrap
from .layout import Page, text_lines, write_pages

__all__ = ["map_figure", "write_map_figure", "write_map_report", "lump_lines"]

_QUANTITIES = {
    "x_m": ("centre x", "length"), "y_m": ("centre y", "length"),
    "radius_m": ("radius", "length"), "depth_m": ("depth of the centre", "length"),
    "ratio": ("stiffness ratio E_lump / E_background", "ratio"),
    "apparent_ratio": ("apparent peak ratio at the surface", "ratio"),
    "apparent_fwhm_m": ("apparent FWHM diameter", "length"),
    "E_background_pa": ("background E away from the lump", "pressure"),
    "tau": ("nugget sd of log E", "ratio"),
}


def _fmt(v: float, kind: str) -> str:
    if not np.isfinite(v):
        return "n/a"
    if kind == "length":
        return format_length(v, 4)
    if kind == "pressure":
        return format_pressure(v, 4)
    return f"{v:.4g}"


def lump_lines(res: MapResult, truth: dict | None = None) -> list[tuple[str, str]]:
    """The summary page's lines: the lump, the background, the hyperparameters, the flags
    (and the simulated phantom's truth, ``truth`` from :func:`palpbayes.sim.map.read_map_truth`,
    beside the estimates)."""
    lat = res.field.lattice
    ok = int((res.points["error"].fillna("") == "").sum())
    lines = [("h", "The map"),
             ("t", f"{len(res.points)} palpations ({ok} fitted) on a {lat.nx} × {lat.ny} "
                   f"lattice, step {format_length(lat.step, 3)}; tip {res.settings.get('tip')}, "
                   f"indentation {format_length(res.settings.get('depth_m', np.nan), 3)}, "
                   f"contact radius {format_length(res.contact_radius, 3)}."),
             ("t", f"Largest P(E > {res.options.threshold:g} × map median) over the map: "
                   f"{res.detection:.3f}." + ("" if res.lump is None else
                   f"  P(a lump with apparent peak ratio > {res.options.threshold:g}): "
                   f"{res.p_lump:.3f}" + ("." if res.lump_found else
                                          " — below the detection level: no lump found.")))]
    med, lo, hi = res.background_interval()
    lines.append(("t", f"Map median E (the field's median over every node, a lump's included: "
                       f"what P(E > k × median) compares with): {format_pressure(med, 4)}, "
                       f"90 % interval [{format_pressure(lo, 4)}, {format_pressure(hi, 4)}]."
                       + ("" if res.lump is None else "  The block's modulus away from a lump "
                          "is the lump model's background E below.")))
    lines.append(("h", "The lump (one spherical inclusion, 90 % intervals)" if res.lump_found
                  else "The largest bump the data allow (no lump found; 90 % intervals)"))
    if res.lump is None:
        lines.append(("t", "No lump model was fitted (see the flags below)."))
    else:
        s = res.lump.summary().set_index("quantity")
        known = _truth_values(truth)
        head = f"{'quantity':40s} {'median':>12s} {'90 % interval':>28s}"
        lines.append(("m", head + ("   truth (simulated)" if known else "")))
        for q, (label, kind) in _QUANTITIES.items():
            r = s.loc[q]
            row = (f"{label:40s} {_fmt(r['median'], kind):>12s} "
                   f"{'[' + _fmt(r['lo'], kind) + ', ' + _fmt(r['hi'], kind) + ']':>28s}")
            if q in known:
                row += f"   {_fmt(known[q], kind)}"
            lines.append(("m", row))
        lines.append(("t", f"Sampler: emcee, acceptance {res.lump.acceptance:.2f}, largest "
                           f"{res.lump.n_steps} steps per walker (first half burn-in)."))
    hs = res.field.hyper_summary()
    lines.append(("h", "The field's hyperparameters (integrated over their grid)"))
    for _, r in hs.iterrows():
        lines.append(("m", f"{r['parameter']:10s} mean {r['mean']:.4g}  sd {r['sd']:.3g}  "
                           f"5–95 % [{r['q05']:.4g}, {r['q95']:.4g}]"))
    lines.append(("h", "Flags"))
    for f in res.flags or ["none: every stage ran without a warning"]:
        lines += [("t", w) for w in wrap("• " + f, 150)]
    return lines


def _truth_values(truth: dict | None) -> dict[str, float]:
    """The lump quantities a simulated phantom's truth record knows."""
    if not truth or not truth.get("has_lump"):
        return {}
    keys = {"x_m": "x_m", "y_m": "y_m", "radius_m": "radius_m", "depth_m": "depth_m",
            "ratio": "ratio", "apparent_ratio": "peak_apparent_ratio",
            "apparent_fwhm_m": "apparent_fwhm_diameter_m", "E_background_pa": "E_background_pa",
            "tau": "heterogeneity"}
    return {q: float(truth[k]) for q, k in keys.items() if truth.get(k) is not None}


_METHODS = (
    "Each trace is fitted by the exact engine (E*, the force offset and the noise integrated out "
    "in closed form, the surface on an adaptive grid; Gaussian noise unless --noise ar1) and "
    "summarised by the mean and sd of log E.  The per-point values exclude the budget's "
    "systematic terms (tip radius, Poisson ratio, sensor gain), common to every point, which "
    "cancel in the ratios the map reports.  The naive map is the paper's least squares per "
    "point.",
    "The field of log E on the palpation lattice has a Gaussian Markov random field prior: the "
    "SPDE form of a Matérn field with smoothness 1 (Lindgren, Rue and Lindström 2011), padded "
    "beyond the map against edge effects, plus a nugget for point-to-point heterogeneity.  Its "
    "sd, range and nugget have penalised-complexity priors and are integrated over a grid "
    "around their posterior mode; the field's draws are exact Gaussian draws for each grid "
    "point (sparse LU, no dense matrix).  The map median is the median of the field over the "
    "map, per draw; P(E > k × map median) is the share of draws above it.",
    "The lump model explains the per-point values by one spherical inclusion seen through a "
    "Boussinesq-weighted Reuss average (palpbayes.inclusion), sampled with emcee.  It is a "
    "model: a real lump that is not spherical, or mechanics beyond the Reuss average, biases "
    "its depth and ratio.  The apparent peak ratio is what the surface shows and is the "
    "best-measured number; the inclusion's own ratio is often bounded only from below.",
)


def _page_text(title: str, lines: list[tuple[str, str]]) -> Page:
    return Page(title, lambda fig: text_lines(fig, lines, top=0.9, size=9))


def _pages(res: MapResult, truth: dict | None) -> list[Page]:
    lump = res.lump_centre()
    centre = None if not truth or not truth.get("has_lump") else (truth["x_m"], truth["y_m"])
    k = res.options.threshold
    bg = res.background_interval()

    def heat(fig: Figure) -> None:
        a1, a2 = fig.subplots(1, 2)
        fig.subplots_adjust(top=0.86, bottom=0.1, wspace=0.3)
        both = np.r_[res.nodes["E_mean_pa"], res.nodes["E_lsq_pa"]] * 1e-3  # one kPa scale
        lim = (float(np.nanmin(both)), float(np.nanmax(both)))
        plot_map_panel(res.nodes, "mean", ax=a1, lump=lump, truth=centre, limits=lim)
        plot_map_panel(res.nodes, "lsq", ax=a2, truth=centre, limits=lim)

    def one(kind: str):
        def draw(fig: Figure) -> None:
            ax = fig.add_axes([0.12, 0.1, 0.62, 0.78])
            plot_map_panel(res.nodes, kind, ax=ax, lump=lump, threshold=k, truth=centre)
        return draw

    def profile(fig: Figure) -> None:
        ax = fig.add_axes([0.08, 0.12, 0.86, 0.74])
        row = None
        if lump:
            ys = res.nodes.groupby("iy")["y_m"].first()
            row = int((ys - lump["y_m"][0]).abs().idxmin())
        plot_profile(res.nodes, row=row, ax=ax, background=bg)

    methods = [("h", "How the map was made")]
    for para in _METHODS:
        methods += [("t", w) for w in wrap(para, 150)] + [("", "")]
    return [
        _page_text("Stiffness map: summary", lump_lines(res, truth)),
        Page("Heat map: posterior mean of E (left) and the naive least-squares map", heat),
        Page("Uncertainty map: posterior sd of E relative to its mean", one("uncertainty")),
        Page(f"Probability map: chance that E > {k:g} × the map median",
              one("probability")),
        Page("Profile through the lump" if lump else "Profile through the largest E", profile),
        _page_text("Methods", methods),
    ]


def map_figure(res: MapResult, truth: dict | None = None) -> Figure:
    """The four panels of ``map.png`` (:func:`palpbayes.plots.maps.plot_map`): a Figure."""
    centre = None if not truth or not truth.get("has_lump") else (truth["x_m"], truth["y_m"])
    return plot_map(res.nodes, lump=res.lump_centre(), threshold=res.options.threshold,
                    background=res.background_interval(), truth_centre=centre)


def write_map_figure(res: MapResult, path: str | os.PathLike,
                     truth: dict | None = None) -> Path:
    """``map.png``: the four panels (:func:`map_figure`), written atomically."""
    fig = map_figure(res, truth)
    return write_with(lambda tmp: fig.savefig(tmp, dpi=130, format="png"), path, suffix=".png")


def write_map_report(res: MapResult, path: str | os.PathLike, *, name: str = "map",
                     truth: dict | None = None, created: str | None = None) -> Path:
    """The map's PDF pages (module docstring), written atomically; return the path."""
    created = created or _dt.date.today().isoformat()
    return write_pages(_pages(res, truth), path, footer=f"palpbayes {__version__} · map {name} · "
                       f"{created}", meta={"Title": f"palpbayes stiffness map: {name}",
                                          "Creator": f"palpbayes {__version__}"})
