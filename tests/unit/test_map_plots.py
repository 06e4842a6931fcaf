"""map.png as a reader sees it: titles in plain words, contours and the lump centre in the
legend, the centre's marker drawn in black under white (visible on a white panel)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.colors import to_rgba

from palpbayes.plots.maps import plot_map, plot_map_panel


def _nodes(n=9, step=3e-3):
    ix, iy = np.meshgrid(np.arange(n), np.arange(n))
    x, y = ix.ravel() * step, iy.ravel() * step
    r2 = (x - 12e-3) ** 2 + (y - 12e-3) ** 2
    E = 50e3 * (1 + 0.2 * np.exp(-r2 / (2 * 4e-3**2)))
    p = 1 / (1 + np.exp(-(E / 50e3 - 1.1) * 60))
    return pd.DataFrame({"ix": ix.ravel(), "iy": iy.ravel(), "x_m": x, "y_m": y,
                         "E_mean_pa": E, "E_rel_sd": 0.01 + 0 * E, "p_stiffer": p,
                         "E_lo_pa": 0.98 * E, "E_hi_pa": 1.02 * E, "E_lsq_pa": E,
                         "E_point_pa": E, "E_point_lo_pa": 0.97 * E, "E_point_hi_pa": 1.03 * E})


LUMP = {"x_m": (12e-3, 11e-3, 13e-3), "y_m": (12e-3, 11.5e-3, 12.5e-3)}


def test_titles_say_what_each_panel_is_in_words():
    fig = plot_map(_nodes(), lump=LUMP, threshold=1.1, background=(50e3, 49e3, 51e3))
    titles = [ax.get_title() for ax in fig.axes]
    assert "uncertainty: sd of E, % of E" in titles
    assert "chance that E > 1.1 × the map median" in titles
    assert not any("background" in t or "P(E" in t for t in titles), titles
    profile = next(ax for ax in fig.axes if ax.get_title().startswith("profile"))
    assert "map median (90 %)" in profile.get_legend_handles_labels()[1]


def test_contours_and_the_lump_centre_are_in_the_legend_and_visible_on_white():
    fig = plot_map_panel(_nodes(), "probability", lump=LUMP, threshold=1.1)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"contour: chance 0.5", "contour: chance 0.9",
            "lump centre (90 % interval)"} <= set(labels), labels
    # the centre's bars: the labelled (legend) layer is black, a white one drawn over it
    # (before, the labelled layer was white: invisible on the white end of this panel)
    bars = [c for c in ax.containers if c.get_label() == "lump centre (90 % interval)"]
    assert len(bars) == 1 and to_rgba(bars[0].lines[0].get_color()) == to_rgba("k")
    others = [c for c in ax.containers if c is not bars[0]]
    assert any(to_rgba(c.lines[0].get_color()) == to_rgba("w") for c in others)
