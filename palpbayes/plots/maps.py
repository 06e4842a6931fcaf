"""Stiffness maps: posterior mean, uncertainty, probability of a stiff lump, a profile.

Every function takes the node table of a map (:data:`palpbayes.maps.run.NODE_COLUMNS`, one row
per lattice node with ``ix``, ``iy``, ``x_m``, ``y_m``) and draws moduli in kPa and positions
in the unit of the map's size (:func:`position_unit`: µm for an AFM map, mm for the robot's).
The estimated lump centre (when there is one) is marked with its 90 % interval; a node
without a fitted point (``n_traces`` 0: no curve, or its fit failed) is marked as a hole.  A
lattice of one row is drawn as a strip of one pixel's height.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

from .style import KPA, METHOD_COLORS, MM, UM, fig_ax

__all__ = ["plot_map", "plot_map_panel", "plot_profile", "map_grid", "position_unit",
           "HOLE_LABEL", "MM_EXTENT"]

#: [m] A map whose positions span less than this is labelled in µm, a larger one in mm.
MM_EXTENT = 1e-3

#: Legend entry of the nodes without a fitted point.
HOLE_LABEL = "no fit (hole)"

#: What each map panel shows: (node column, title, colour-bar label, colormap, scale).
PANELS: dict[str, tuple[str, str, str, str, float]] = {
    "mean": ("E_mean_pa", "stiffness: E, posterior mean", "E [kPa]", "viridis", KPA),
    "uncertainty": ("E_rel_sd", "uncertainty: sd of E, % of E", "sd / mean [%]", "magma",
                    100.0),
    "probability": ("p_stiffer", "chance that E > k × the map median", "probability", "RdPu",
                    1.0),
    "lsq": ("E_lsq_pa", "naive per-point least squares", "E [kPa]", "viridis", KPA),
}


def map_grid(nodes: pd.DataFrame, column: str) -> np.ndarray:
    """The node column as a (ny, nx) array (NaN where a node has no value)."""
    nx, ny = int(nodes["ix"].max()) + 1, int(nodes["iy"].max()) + 1
    out = np.full((ny, nx), np.nan)
    out[nodes["iy"].to_numpy(int), nodes["ix"].to_numpy(int)] = nodes[column].to_numpy(float)
    return out


def position_unit(nodes: pd.DataFrame) -> tuple[str, float]:
    """The unit of a map's positions on its axes and the factor from metres to it.

    Parameters
    ----------
    nodes
        Node table of a map (``x_m``, ``y_m`` [m]).

    Returns
    -------
    tuple of (str, float)
        ``("µm", 1e6)`` when the lattice spans less than :data:`MM_EXTENT` along both axes
        (an AFM map), ``("mm", 1e3)`` otherwise (the robot's maps).
    """
    span = max(float(np.ptp(nodes["x_m"].to_numpy(float))),
               float(np.ptp(nodes["y_m"].to_numpy(float))))
    return ("µm", UM) if span < MM_EXTENT else ("mm", MM)


def _half_step(nodes: pd.DataFrame, scale: float) -> float:
    """Half the lattice step in axis units (the half-width of a pixel)."""
    for pos, index in (("x_m", "ix"), ("y_m", "iy")):
        n = int(nodes[index].max())
        if n > 0:
            return 0.5 * float(np.ptp(nodes[pos].to_numpy(float))) * scale / n
    return 0.5  # a single node: any pixel size


def _extent(nodes: pd.DataFrame, scale: float) -> tuple[float, float, float, float]:
    """imshow extent in axis units: one square pixel per node, a one-row map a strip."""
    x, y = nodes["x_m"].to_numpy() * scale, nodes["y_m"].to_numpy() * scale
    h = _half_step(nodes, scale)
    return (x.min() - h, x.max() + h, y.min() - h, y.max() + h)


def _mark_holes(ax: Axes, nodes: pd.DataFrame, scale: float) -> None:
    """An 'x' at every node without a fitted point (``n_traces`` 0), white under black."""
    if "n_traces" not in nodes:
        return
    holes = nodes[nodes["n_traces"].fillna(0).to_numpy() == 0]
    if holes.empty:
        return
    x, y = holes["x_m"].to_numpy() * scale, holes["y_m"].to_numpy() * scale
    ax.plot(x, y, "x", color="w", ms=7, mew=3.0, zorder=3)
    ax.plot(x, y, "x", color="k", ms=6, mew=1.3, zorder=4, label=HOLE_LABEL)


def _mark_lump(ax: Axes, lump: Mapping[str, tuple[float, float, float]] | None,
               scale: float) -> None:
    """Cross at the lump centre with its interval in x and y (axis units: ``scale`` per m)."""
    if not lump:
        return
    (cx, xlo, xhi), (cy, ylo, yhi) = lump["x_m"], lump["y_m"]
    err = {"xerr": [[(cx - xlo) * scale], [(xhi - cx) * scale]],
           "yerr": [[(cy - ylo) * scale], [(yhi - cy) * scale]], "fmt": "+"}
    # black under white: seen on a dark map and on a white one (and in the legend)
    ax.errorbar([cx * scale], [cy * scale], color="k", ms=12, mew=3.5, capsize=5,
                capthick=3.5, lw=3.0, label="lump centre (90 % interval)", **err)
    ax.errorbar([cx * scale], [cy * scale], color="w", ms=10, mew=1.5, capsize=4,
                capthick=1.5, lw=1.2, **err)


def _colour_bar(fig: Figure, ax: Axes, im, label: str, *, strip: bool) -> None:
    """The map's colour bar, as long as the map's image is tall: where the layout puts it,
    beside the axes' box, but at each draw its length moved onto the image, which the equal
    aspect makes lower (or narrower) than the box; a one-row strip's bar lies under it, as
    wide.  Its box aspect (length / thickness) is kept, so its thickness follows."""
    cbar = fig.colorbar(im, ax=ax, label=label, location="bottom" if strip else "right")
    laid_out = cbar.ax.get_axes_locator()  # the colour bar's own (it places any extends)

    def on_the_image(cax: Axes, renderer) -> Bbox:
        slot = laid_out(cax, renderer)  # where the layout put the bar, in figure fractions
        aspect = cax.get_box_aspect() or (0.05 if strip else 20.0)  # height / width
        w, h = fig.get_size_inches()
        ax.apply_aspect()
        image = ax.get_position(original=False)
        if strip:
            thick = image.width * w * aspect / h
            under = ax.get_tightbbox(renderer).transformed(fig.transFigure.inverted()).y0
            return Bbox.from_bounds(image.x0, under - 0.01 - thick, image.width, thick)
        return Bbox.from_bounds(slot.x0, image.y0, image.height * h / aspect / w, image.height)

    cbar.ax.set_axes_locator(on_the_image)


def plot_map_panel(nodes: pd.DataFrame, kind: str = "mean", *, ax: Axes | None = None,
                   lump: Mapping[str, tuple[float, float, float]] | None = None,
                   threshold: float | None = None, truth: tuple[float, float] | None = None,
                   title: str | None = None,
                   limits: tuple[float, float] | None = None) -> Figure:
    """One map: ``kind`` is ``mean``, ``uncertainty``, ``probability`` or ``lsq``; nodes
    without a fitted point are marked ``x`` (:data:`HOLE_LABEL` in the legend).

    Parameters
    ----------
    nodes
        Node table of a map.
    kind
        Which panel (:data:`PANELS`).
    ax
        Axes to draw on (a new figure otherwise).
    lump
        ``{"x_m": (median, lo, hi), "y_m": (...)}`` [m] of the estimated centre.
    threshold
        k of the probability panel (shown in the title).
    truth
        [m] True lump centre of a simulated phantom (a circle).
    title
        Overrides the panel's title.
    limits
        Colour-scale limits in the panel's units (e.g. the same kPa range for two maps).
    """
    if kind not in PANELS:
        raise ValueError(f"unknown map panel {kind!r}; use one of {', '.join(PANELS)}")
    col, default_title, label, cmap, scale = PANELS[kind]
    fig, ax = fig_ax(ax, (5.6, 4.6))
    z = map_grid(nodes, col) * scale
    kw = {"vmin": 0.0, "vmax": 1.0} if kind == "probability" else {}
    if limits is not None:
        kw = {"vmin": limits[0], "vmax": limits[1]}
    unit, scale = position_unit(nodes)
    im = ax.imshow(z, origin="lower", extent=_extent(nodes, scale), cmap=cmap,
                   interpolation="nearest", aspect="equal", **kw)
    _colour_bar(fig, ax, im, label, strip=int(nodes["iy"].max()) == 0)
    if kind == "probability" and np.isfinite(z).any() and np.nanmax(z) >= 0.5:
        xs = np.unique(nodes["x_m"]) * scale
        ys = np.unique(nodes["y_m"]) * scale
        if xs.size > 1 and ys.size > 1:
            ax.contour(xs, ys, z, levels=[0.5, 0.9], colors=["0.3", "k"], linewidths=[0.8, 1.2])
            for colour, width, text in (("0.3", 0.8, "chance 0.5"), ("k", 1.2, "chance 0.9")):
                ax.plot([], [], color=colour, lw=width, label=f"contour: {text}")
    _mark_holes(ax, nodes, scale)
    _mark_lump(ax, lump, scale)
    if truth is not None:
        ax.plot([truth[0] * scale], [truth[1] * scale], "o", mfc="none", mec=METHOD_COLORS["truth"],
                ms=12, mew=2, label="true centre")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
    t = title or default_title
    if kind == "probability" and threshold is not None:
        t = f"chance that E > {threshold:g} × the map median"
    ax.set(xlabel=f"x [{unit}]", ylabel=f"y [{unit}]", title=t)
    return fig


def plot_profile(nodes: pd.DataFrame, *, row: int | None = None, ax: Axes | None = None,
                 background: tuple[float, float, float] | None = None,
                 truth: np.ndarray | None = None, title: str = "") -> Figure:
    """E along one lattice row (default: the row of the largest posterior mean, titled so;
    a row given is titled as the lump's).

    Posterior mean with its 90 % band, each point's own posterior (median, interval), the
    naive least-squares value (in the legend only when that fit succeeded somewhere on the
    row: on an AFM force map it may fail everywhere), the background level and, along the
    bottom, an ``x`` at every node without a fitted point (:data:`HOLE_LABEL`).

    Parameters
    ----------
    nodes
        Node table of a map.
    row
        Lattice row index iy.
    background
        [Pa] (median, lo, hi) of the map median (the reference of the probability panel).
    truth
        [Pa] True apparent modulus at each node of the row (simulated phantoms).
    """
    what = "the lump"
    if row is None:
        row = int(nodes.loc[nodes["E_mean_pa"].idxmax(), "iy"])
        what = "the largest E"  # no lump to go through (e.g. an AFM map, lump model off)
    r = nodes[nodes["iy"] == row].sort_values("ix")
    fig, ax = fig_ax(ax, (7.0, 4.0))
    unit, scale = position_unit(nodes)
    x = r["x_m"].to_numpy() * scale
    c = METHOD_COLORS["bayes"]
    ax.fill_between(x, r["E_lo_pa"] * KPA, r["E_hi_pa"] * KPA, color=c, alpha=0.25, lw=0,
                    label="map: 90 % band")
    ax.plot(x, r["E_mean_pa"] * KPA, color=c, lw=1.8, label="map: posterior mean")
    pts = r[np.isfinite(r["E_point_pa"])]
    if len(pts):
        ax.errorbar(pts["x_m"] * scale, pts["E_point_pa"] * KPA,
                    yerr=[(pts["E_point_pa"] - pts["E_point_lo_pa"]) * KPA,
                          (pts["E_point_hi_pa"] - pts["E_point_pa"]) * KPA],
                    fmt="o", ms=3, color="0.25", capsize=2, lw=0.8,
                    label="each point's own posterior")
    if np.isfinite(r["E_lsq_pa"].to_numpy(float)).any():  # none (an AFM map's): no entry
        ax.plot(r["x_m"] * scale, r["E_lsq_pa"] * KPA, "x", color=METHOD_COLORS["lsq"], ms=5,
                label="naive least squares")
    if background is not None:
        med, lo, hi = background
        ax.axhspan(lo * KPA, hi * KPA, color="0.6", alpha=0.2, lw=0)
        ax.axhline(med * KPA, color="0.4", lw=1, ls="--", label="map median (90 %)")
    if truth is not None:
        ax.plot(x, np.asarray(truth) * KPA, color=METHOD_COLORS["truth"], lw=1.2,
                label="true apparent E")
    if "n_traces" in r:
        holes = r[r["n_traces"].fillna(0).to_numpy() == 0]
        if len(holes):  # along the bottom edge, whatever the E scale
            ax.plot(holes["x_m"] * scale, np.full(len(holes), 0.03), "x", color="k", ms=6,
                    mew=1.3, transform=ax.get_xaxis_transform(), label=HOLE_LABEL)
    y_row = float(r["y_m"].iloc[0]) * scale
    ax.set(xlabel=f"x [{unit}]", ylabel="E [kPa]",
           title=title or f"profile through {what} (row y = {y_row:.3g} {unit})")
    ax.legend(fontsize=7, loc="upper left")
    return fig


def plot_map(nodes: pd.DataFrame, *, lump: Mapping | None = None, threshold: float = 1.1,
             background: tuple[float, float, float] | None = None,
             truth_centre: tuple[float, float] | None = None, title: str = "") -> Figure:
    """The four panels of a map in one figure (``map.png``): mean, uncertainty, probability
    and the profile through the lump."""
    fig = Figure(figsize=(12.0, 9.0), layout="constrained")
    axes = fig.subplots(2, 2)
    plot_map_panel(nodes, "mean", ax=axes[0, 0], lump=lump, truth=truth_centre)
    plot_map_panel(nodes, "uncertainty", ax=axes[0, 1], lump=lump)
    plot_map_panel(nodes, "probability", ax=axes[1, 0], lump=lump, threshold=threshold,
                   truth=truth_centre)
    row = None
    if lump:
        iy = np.unique(nodes["iy"])
        ys = np.array([nodes.loc[nodes["iy"] == k, "y_m"].iloc[0] for k in iy])
        row = int(iy[np.argmin(np.abs(ys - lump["y_m"][0]))])
    plot_profile(nodes, row=row, ax=axes[1, 1], background=background)
    if title:
        fig.suptitle(title)
    return fig
