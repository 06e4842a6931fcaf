"""An active search on paper: where it pressed, in what order, and P(lump) after each press.

:func:`plot_search` draws two panels for a :class:`palpbayes.active.SearchState`: the
footprint with the presses numbered in order (one marker per press depth when the search
chose them) over the posterior probability that the
apparent modulus exceeds k × the background (the level set the search maps), the lump's
posterior centre with its 90 % disc, keep-out zones and, for a phantom, the true centre;
and P(lump) after each press against the decision thresholds.  Positions in mm.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from matplotlib.ticker import NullFormatter, ScalarFormatter

from .style import MM

__all__ = ["plot_search"]


def plot_search(state, *, rule=None, hist: pd.DataFrame | None = None,
                truth: tuple[float, float] | None = None, title: str | None = None) -> Figure:
    """The press sequence and P(lump) after each press (module docstring).

    Parameters
    ----------
    state
        A :class:`~palpbayes.active.SearchState` with at least one press.
    rule
        The :class:`~palpbayes.active.SearchStopRule` (its thresholds are drawn).
    hist
        :func:`palpbayes.active.search.history` of ``state`` (computed when None).
    truth
        [m] The true lump centre of a phantom, marked when given.
    """
    from ..active.criteria import level_probability
    from ..active.search import SearchStopRule, history

    rule = rule or SearchStopRule()
    if state.n == 0:
        raise ValueError("plot_search: the state has no press yet")
    hist = history(state, rule) if hist is None else hist
    post = state.posterior()
    x0, x1, y0, y1 = state.footprint
    gx, gy = np.linspace(x0, x1, 43), np.linspace(y0, y1, 43)
    X, Y = np.meshgrid(gx, gy)
    P = level_probability(post, X.ravel(), Y.ravel(), state.level).reshape(X.shape)

    fig = Figure(figsize=(11.0, 4.6), layout="constrained")
    ax, bx = fig.subplots(1, 2, width_ratios=(1.05, 1.0))
    im = ax.imshow(P, origin="lower", extent=(x0 * MM, x1 * MM, y0 * MM, y1 * MM),
                   cmap="RdPu", vmin=0.0, vmax=1.0, interpolation="nearest")
    fig.colorbar(im, ax=ax, label=f"P(E > {state.level:.3g} × background)")
    px, py = state.presses["x_m"].to_numpy(float), state.presses["y_m"].to_numpy(float)
    ax.plot(px * MM, py * MM, "-", color="0.55", lw=0.6, zorder=2)
    order = np.arange(1, px.size + 1)
    depth = state.depth_index()
    depth = np.zeros(px.size, int) if depth is None else depth
    for j in np.unique(depth):  # one marker per press depth, when the search chose them
        at = depth == j
        label = (None if state.press_depths is None else
                 f"pressed {state.press_depths.depths[j] * MM:g} mm ({at.sum()})")
        sc = ax.scatter(px[at] * MM, py[at] * MM, c=order[at], cmap="viridis", s=22,
                        vmin=1, vmax=max(2, px.size), edgecolor="k", lw=0.4, zorder=3,
                        marker="os^D"[j % 4], label=label)
    fig.colorbar(sc, ax=ax, label="press number", location="left")
    xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    for i in range(0, px.size, max(1, px.size // 12)):
        # towards the footprint's middle, so that a press on its edge keeps its number
        # inside the panel (a number above the top edge overprinted the title)
        right, up = px[i] <= xm, py[i] <= ym
        ax.annotate(str(i + 1), (px[i] * MM, py[i] * MM), fontsize=7,
                    xytext=(3 if right else -3, 3 if up else -3), textcoords="offset points",
                    ha="left" if right else "right", va="bottom" if up else "top",
                    annotation_clip=True)
    for zx, zy, r in state.keep_out:
        ax.add_patch(Circle((zx * MM, zy * MM), r * MM, fill=False, hatch="///",
                            color="0.3", label="keep out"))
    if post.p_lump >= 0.5:
        cx, cy = post.centre
        r = post.centre_radius(rule.level)
        ax.add_patch(Circle((cx * MM, cy * MM), r * MM, fill=False, color="tab:orange",
                            lw=1.5, label=f"centre, {100 * rule.level:g} % disc"))
        ax.plot(cx * MM, cy * MM, "+", color="tab:orange", ms=10, mew=1.8)
    if truth is not None:
        ax.plot(truth[0] * MM, truth[1] * MM, "x", color="tab:red", ms=9, mew=2,
                label="true centre")
    ax.set_xlim(x0 * MM, x1 * MM)
    ax.set_ylim(y0 * MM, y1 * MM)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    head = f"{state.n} presses, P(lump) = {post.p_lump:.3f}"
    if title:  # a long title spans the figure, above both panels and the colour bars
        fig.suptitle(title)
    ax.set_title(head)

    bx.plot(hist["n"], hist["p_lump"], "o-", ms=3, color="tab:purple", label="P(lump)")
    bx.axhline(rule.p_decide, color="tab:red", ls="--", lw=1,
               label=f"decide: lump (and centre within {rule.centre_radius * MM:g} mm)")
    bx.axhline(1 - rule.p_decide, color="tab:blue", ls="--", lw=1, label="decide: no lump")
    bx.set_ylim(-0.02, 1.02)
    bx.set_xlabel("presses")
    bx.set_ylabel("P(lump) after the press")
    r2 = bx.twinx()
    r2.plot(hist["n"], hist["centre_radius_m"] * MM, color="tab:orange", lw=1, alpha=0.8)
    r2.axhline(rule.centre_radius * MM, color="tab:orange", ls=":", lw=1)
    r2.set_ylabel(f"centre's {100 * rule.level:g} % radius [mm] (if a lump)",
                  color="tab:orange")
    r2.set_yscale("log")
    r2.yaxis.set_major_formatter(ScalarFormatter())
    r2.yaxis.set_minor_formatter(NullFormatter())
    bx.set_title("P(lump) after each press")
    # one legend under both panels: inside either it sat on the presses or on the curves
    handles, labels = (a + b for a, b in zip(ax.get_legend_handles_labels(),
                                             bx.get_legend_handles_labels(), strict=True))
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 3),
               fontsize=8)
    return fig
