"""map.png as a reader sees it: titles in plain words, contours and the lump centre in the
legend, the centre's marker drawn in black under white (visible on a white panel), positions
in µm on an AFM map and in mm on the robot's, holes marked, a one-row map drawn."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba

from palpbayes.plots.maps import HOLE_LABEL, plot_map, plot_map_panel, plot_profile, position_unit


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


def _afm_nodes(nx=4, ny=4, step=5e-6, holes=((1, 2), (3, 0))):
    """An AFM-sized map (5 µm steps) with nodes that have no fitted point."""
    nodes = _nodes(n=max(nx, ny), step=step)
    nodes = nodes[(nodes["ix"] < nx) & (nodes["iy"] < ny)].reset_index(drop=True)
    nodes["n_traces"] = 1
    for i, j in holes:
        at = (nodes["ix"] == i) & (nodes["iy"] == j)
        nodes.loc[at, "n_traces"] = 0
        nodes.loc[at, ["E_point_pa", "E_point_lo_pa", "E_point_hi_pa", "E_lsq_pa"]] = np.nan
    return nodes


def _hole_markers(ax):
    return [ln for ln in ax.get_lines() if ln.get_label() == HOLE_LABEL]


def test_an_afm_map_reads_in_micrometres_and_a_robot_map_in_millimetres():
    fig = plot_map(_afm_nodes(), background=(50e3, 49e3, 51e3))
    panels = [ax for ax in fig.axes if ax.get_xlabel().startswith("x [")]
    assert len(panels) == 4  # three maps and the profile
    assert {ax.get_xlabel() for ax in panels} == {"x [µm]"}
    assert all(ax.get_ylabel() == "y [µm]" for ax in panels if ax.images)
    profile = next(ax for ax in fig.axes if ax.get_title().startswith("profile"))
    assert profile.get_title().endswith(" µm)")
    # the image spans the lattice in µm: 4 nodes of 5 µm, each pixel centred on its node
    img = next(ax for ax in fig.axes if ax.images).images[0]
    np.testing.assert_allclose(img.get_extent(), [-2.5, 17.5, -2.5, 17.5])
    robot = plot_map_panel(_nodes(), "mean").axes[0]  # 9 × 9 nodes of 3 mm
    assert (robot.get_xlabel(), robot.get_ylabel()) == ("x [mm]", "y [mm]")
    assert position_unit(_nodes()) == ("mm", 1e3)


def test_the_lump_cross_is_drawn_in_the_axis_unit():
    lump_um = {k: tuple(v * 1e-3 for v in lo_hi) for k, lo_hi in LUMP.items()}  # 12 µm
    ax = plot_map_panel(_afm_nodes(), "mean", lump=lump_um).axes[0]
    bars = [c for c in ax.containers if c.get_label() == "lump centre (90 % interval)"]
    x, y = bars[0].lines[0].get_data()
    assert (float(x[0]), float(y[0])) == pytest.approx((12.0, 12.0))


def test_holes_are_marked_in_every_map_panel_and_named_in_the_legend():
    nodes = _afm_nodes()
    for kind in ("mean", "uncertainty", "probability", "lsq"):
        ax = plot_map_panel(nodes, kind).axes[0]
        (marks,) = _hole_markers(ax)
        assert marks.get_marker() == "x" and to_rgba(marks.get_color()) == to_rgba("k")
        got = sorted(zip(*marks.get_data(), strict=True))
        assert got == [(pytest.approx(5.0), pytest.approx(10.0)),
                       (pytest.approx(15.0), pytest.approx(0.0))], kind
        assert HOLE_LABEL in [t.get_text() for t in ax.get_legend().get_texts()]
    # a map without holes draws none
    full = _afm_nodes(holes=())
    assert not _hole_markers(plot_map_panel(full, "mean").axes[0])


def test_the_profile_marks_the_holes_of_its_row():
    nodes = _afm_nodes()
    ax = plot_profile(nodes, row=2).axes[0]
    (marks,) = _hole_markers(ax)
    np.testing.assert_allclose(marks.get_data()[0], [5.0])
    assert not _hole_markers(plot_profile(nodes, row=1).axes[0])


def test_a_one_row_map_is_a_strip_of_square_pixels():
    nodes = _afm_nodes(nx=4, ny=1, step=78e-9, holes=((2, 0),))
    ax = plot_map_panel(nodes, "mean").axes[0]
    assert ax.images[0].get_array().shape == (1, 4)
    x0, x1, y0, y1 = ax.images[0].get_extent()
    assert (x1 - x0, y1 - y0) == (pytest.approx(4 * 0.078), pytest.approx(0.078))
    assert ax.get_xlabel() == "x [µm]" and len(_hole_markers(ax)) == 1


def _drawn(fig):
    """The figure drawn by Agg (the positions of aspect-equal axes are then final)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    return fig


def _bars(fig):
    """(map axes, its colour bar's axes) of every map panel of a figure."""
    return [(ax, ax.images[0].colorbar.ax) for ax in fig.axes if ax.images
            and ax.images[0].colorbar is not None]


def _assert_as_tall(fig, n):
    pairs = _bars(_drawn(fig))
    assert len(pairs) == n
    for ax, cax in pairs:
        a, c = ax.get_position(), cax.get_position()
        # before: 0.684 of the page beside a map of 0.381 (the report), 1.8x too tall in
        # map.png on a wide lattice
        assert c.height == pytest.approx(a.height, abs=2e-3), ax.get_title()
        assert c.y0 == pytest.approx(a.y0, abs=2e-3) and c.x0 > a.x1, ax.get_title()


def test_colour_bars_are_as_tall_as_their_maps_in_map_png_and_the_report():
    nodes = _nodes()
    wide = nodes[nodes["iy"] < 4]  # 9 x 4 nodes: the image is far lower than its box
    _assert_as_tall(plot_map(wide, lump=LUMP, background=(50e3, 49e3, 51e3)), 3)
    _assert_as_tall(plot_map(nodes, lump=LUMP, background=(50e3, 49e3, 51e3)), 3)
    # the report's heat page: two maps side by side on a landscape A4 page, no layout engine
    from matplotlib.figure import Figure

    page = Figure(figsize=(11.69, 8.27))
    a1, a2 = page.subplots(1, 2)
    page.subplots_adjust(top=0.86, bottom=0.1, wspace=0.3)
    plot_map_panel(nodes, "mean", ax=a1)
    plot_map_panel(nodes, "lsq", ax=a2)
    _assert_as_tall(page, 2)


def test_a_strips_colour_bar_is_as_wide_as_the_strip_and_under_its_labels():
    fig = _drawn(plot_map_panel(_afm_nodes(nx=4, ny=1, step=78e-9, holes=()), "mean"))
    ((ax, cax),) = _bars(fig)
    a, c = ax.get_position(), cax.get_position()
    assert c.width == pytest.approx(a.width, abs=2e-3) and c.x0 == pytest.approx(a.x0, abs=2e-3)
    below = ax.get_tightbbox(fig.canvas.get_renderer())  # the strip with its x labels
    assert cax.get_window_extent().y1 <= below.y0
    assert c.height < 0.2 * c.width


def test_the_profile_legend_names_only_what_it_draws():
    """An AFM map has no least-squares value (that fit fails on its curves): map.png's legend
    listed 'naive least squares' with no marker drawn."""
    nodes = _afm_nodes(holes=())
    nodes["E_lsq_pa"] = np.nan
    for frame in (nodes, _nodes()):
        ax = plot_profile(frame, row=1, background=(50e3, 49e3, 51e3)).axes[0]
        handles, labels = ax.get_legend_handles_labels()
        for h, label in zip(handles, labels, strict=True):
            lines = h.lines[0] if hasattr(h, "lines") else h  # an errorbar's data line
            if hasattr(lines, "get_ydata"):
                assert np.isfinite(np.asarray(lines.get_ydata(), float)).any(), label
        assert ("naive least squares" in labels) == bool(np.isfinite(frame["E_lsq_pa"]).any())
