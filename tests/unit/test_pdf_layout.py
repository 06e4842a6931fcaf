"""The layout check (:mod:`palpbayes.reporting.layout_check`) and the layout helpers it keeps
honest: measured wrapping, tables whose cells hold their text."""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from palpbayes.reporting.layout import PAGE_SIZE, text_height, text_lines, text_width, wrap_to
from palpbayes.reporting.layout_check import layout_problems, text_boxes
from palpbayes.reporting.tables import draw_table


def _page() -> Figure:
    return Figure(figsize=PAGE_SIZE)


def test_a_clean_page_has_no_problem():
    fig = _page()
    fig.text(0.1, 0.9, "a title", fontsize=14)
    fig.text(0.1, 0.8, "a line of text below it")
    assert layout_problems(fig) == []


def test_overlapping_texts_and_a_line_off_the_page_are_found():
    fig = _page()
    fig.text(0.1, 0.5, "first text drawn here")
    fig.text(0.12, 0.505, "second text over it")
    fig.text(0.9, 0.3, "a line that runs off the right edge of the page")
    kinds = sorted(p.kind for p in layout_problems(fig, page="p"))
    assert kinds == ["off page", "overlap"]


def test_hidden_and_empty_texts_do_not_count():
    fig = _page()
    fig.text(0.1, 0.5, "shown")
    fig.text(0.1, 0.5, "hidden").set_visible(False)
    fig.text(0.1, 0.5, "  ")
    assert [b.text for b in text_boxes(fig)] == ["shown"]


def test_a_raw_matplotlib_table_runs_its_cells_together_and_draw_table_does_not():
    cells = [["872.9 [857.6, 887.2]", "2.196 [2.101, 2.291]", "Medium_paraboloid_v100_r01"]]
    fig = _page()
    ax = fig.add_axes((0.1, 0.5, 0.2, 0.1))
    ax.set_axis_off()
    tab = ax.table(cellText=cells, colLabels=["E*", "drag", "trace"], loc="upper center")
    tab.auto_set_font_size(False)
    tab.set_fontsize(8)
    assert any(p.kind == "cell" for p in layout_problems(fig))

    fig = _page()
    height = draw_table(fig.add_axes((0.1, 0.5, 0.2, 0.1)),
                        pd.DataFrame(cells, columns=["E*", "drag", "trace"]), fontsize=8)
    assert layout_problems(fig) == []
    assert height > 0.1 * 0.5  # rows grew to hold the wrapped cells


def test_long_notes_wrap_in_full_in_a_left_aligned_column():
    note = "; ".join(f"flag number {i} with a long explanation of what went wrong"
                     for i in range(6))
    fig = _page()
    df = pd.DataFrame([{"Trace": "t1", "notes": note.replace("; ", "\n")}])
    draw_table(fig.add_axes((0.05, 0.5, 0.9, 0.3)), df, left=("notes",), min_fontsize=7.5)
    assert layout_problems(fig) == []
    shown = " ".join(" ".join(b.text for b in text_boxes(fig)).split())
    assert all(f"flag number {i}" in shown for i in range(6))


def test_measured_wrapping_fits_its_width_and_text_lines_returns_its_bottom():
    text = "word " * 200
    lines = wrap_to(text, 300.0, 9.0)
    assert all(text_width(ln, 9.0) <= 300.0 for ln in lines)
    assert " ".join(ln.strip() for ln in lines).split() == text.split()
    fig = _page()
    bottom = text_lines(fig, [("t", text)], top=0.9, left=0.05, size=9.0)
    assert abs((0.9 - bottom) - text_height([("t", text)], size=9.0, left=0.05)) < 1e-9
    assert layout_problems(fig) == []
