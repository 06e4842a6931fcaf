"""``palpbayes next --plot``'s figure (plots.active.plot_search) after a long search: the
press numbers stay inside their panel, clear of the title, and the legend sits on no data."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from palpbayes.active import SearchState
from palpbayes.inclusion import Inclusion
from palpbayes.plots.active import plot_search
from palpbayes.sim.phantom import MapPhantom

FOOT = (0.0, 0.042, 0.0, 0.042)
PH = MapPhantom(inclusion=Inclusion(x=0.014, y=0.027, depth=5.5e-3, radius=5e-3, ratio=10.0))


@pytest.fixture(scope="module")
def long_search():
    """217 presses, the last 12 along the top edge (217 in the top right corner), with a
    history of the shape a search has (computing it would take minutes)."""
    rng = np.random.default_rng(0)
    x = np.r_[rng.uniform(0, 0.042, 205), np.linspace(0, 0.042, 12)]
    y = np.r_[rng.uniform(0, 0.042, 205), np.full(12, 0.042)]
    presses = pd.DataFrame({"x_m": x, "y_m": y, "logE_sd": 0.0015,
                            "logE_mean": np.log(PH.apparent_modulus(x, y))})
    state = SearchState(presses, FOOT, PH.contact_radius, PH.thickness)
    n = np.arange(1, x.size + 1)
    hist = pd.DataFrame({"n": n, "p_lump": np.minimum(1.0, 0.3 + n / 60),
                         "centre_radius_m": 0.02 / np.sqrt(n)})
    return state, hist


@pytest.mark.parametrize("title", [None, "phantom 1 (no lump): 217 presses, eig"])
def test_press_numbers_stay_in_their_panel_clear_of_the_titles(long_search, title):
    state, hist = long_search
    fig = plot_search(state, hist=hist, title=title)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = next(a for a in fig.axes if a.get_title().startswith("217 presses"))
    numbers = [t for t in ax.texts if t.get_text().isdigit()]
    assert "217" in {t.get_text() for t in numbers}
    titles = [ax.title.get_window_extent(renderer)]
    if fig._suptitle is not None:
        titles.append(fig._suptitle.get_window_extent(renderer))
    panel = ax.get_window_extent(renderer)
    for t in numbers:
        box = t.get_window_extent(renderer)
        # before: '145' and '217' above the top edge, over the title and the colour bar
        assert not any(box.overlaps(b) for b in titles), t.get_text()
        assert (panel.x0 <= box.x0 and box.x1 <= panel.x1 and panel.y0 <= box.y0
                and box.y1 <= panel.y1), t.get_text()


def test_the_legend_covers_no_data_and_names_what_is_drawn(long_search):
    state, hist = long_search
    fig = plot_search(state, hist=hist)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend())]
    for legend in legends:  # before: one in each panel, on the presses and on the curves
        box = legend.get_window_extent(renderer)
        for a in fig.axes:
            assert not box.overlaps(a.get_window_extent(renderer)), a.get_title()
    drawn = {ln.get_label() for a in fig.axes for ln in (*a.get_lines(), *a.patches)}
    labels = [t.get_text() for legend in legends for t in legend.get_texts()]
    assert set(labels) <= drawn and "P(lump)" in labels
    assert any(lab.startswith("centre, 90 %") for lab in labels)  # P(lump) >= 0.5: its disc


def test_a_search_over_depths_marks_each_press_depth():
    from palpbayes.active.depth import PressDepths

    rng = np.random.default_rng(1)
    x, y = rng.uniform(0, 0.042, (2, 30))
    depth = np.where(np.arange(30) % 4 == 0, 0.004, 0.002)
    presses = pd.DataFrame({"x_m": x, "y_m": y, "logE_sd": 0.0015, "depth_m": depth,
                            "logE_mean": np.log([float(PH.apparent_modulus(a, b, d))
                                                 for a, b, d in zip(x, y, depth,
                                                                    strict=True)])})
    choice = PressDepths.for_tip(PH.tip, (0.002, 0.004))
    state = SearchState(presses, FOOT, choice.contact_radii[0], PH.thickness,
                        press_depths=choice)
    hist = pd.DataFrame({"n": np.arange(1, 31), "p_lump": 0.5, "centre_radius_m": 0.01})
    fig = plot_search(state, hist=hist)
    labels = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert "pressed 2 mm (22)" in labels and "pressed 4 mm (8)" in labels
    ax = fig.axes[0]
    sizes = sorted(len(c.get_offsets()) for c in ax.collections if len(c.get_offsets()))
    assert sizes == [8, 22]
