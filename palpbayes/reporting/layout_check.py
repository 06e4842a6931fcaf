"""A page's text layout checked before it is saved: text drawn over text, text off the page,
a table cell's text wider than its cell.

:func:`layout_problems` draws a matplotlib :class:`~matplotlib.figure.Figure` with the Agg
renderer, records every text artist the drawing actually paints (figure and subfigure texts,
titles, axis labels, the tick labels inside the view, legends, annotations, table cells) with its
window extent, and returns what a reader would see as overprinted or clipped.
:func:`watch_pages` runs it on every page :func:`~palpbayes.reporting.layout.write_pages` writes
(the campaign report, a single fit's, a map's, the viscoelastic fits'), before the page is saved::

    with watch_pages() as problems:
        report(folder)
    assert not problems, problems
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure
from matplotlib.table import Table
from matplotlib.text import Text
from matplotlib.transforms import Bbox

__all__ = ["LayoutProblem", "TextBox", "text_boxes", "layout_problems", "watch_pages",
           "page_observers", "TOLERANCE_PT"]

#: Overlaps and overhangs up to this many points are ignored (rounding of the glyph boxes).
TOLERANCE_PT = 0.75


@dataclass(frozen=True)
class TextBox:
    """One painted text artist.

    Attributes
    ----------
    text
        Its string.
    box
        Its window extent [points from the page's lower-left corner].
    cell
        For a table cell's text, the cell's own box [points]; None otherwise.
    """

    text: str
    box: tuple[float, float, float, float]
    cell: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class LayoutProblem:
    """What is wrong on a page.

    Attributes
    ----------
    kind
        ``"overlap"`` (two texts drawn over each other), ``"off page"`` (a text crosses the
        page's edge) or ``"cell"`` (a table cell's text is wider or taller than its cell).
    texts
        The text(s) concerned (two for an overlap).
    amount
        The overlap's smaller side, or how far the text crosses the page's or cell's edge
        [points].
    page
        The page's title, when known (:func:`watch_pages`).
    """

    kind: str
    texts: tuple[str, ...]
    amount: float
    page: str = ""

    def __str__(self) -> str:
        where = f"{self.page!r}: " if self.page else ""
        shown = " / ".join(repr(t if len(t) <= 60 else t[:57] + "...") for t in self.texts)
        return f"{where}{self.kind} by {self.amount:.1f} pt: {shown}"


def _cells(fig: Figure) -> dict[int, Bbox]:
    """id(cell text) -> the cell's window extent, for every table of the figure."""
    out: dict[int, Bbox] = {}
    for tab in fig.findobj(Table):
        for cell in tab.get_celld().values():
            if cell.get_visible():
                out[id(cell.get_text())] = cell.get_window_extent()
    return out


def text_boxes(fig: Figure) -> list[TextBox]:
    """Draw ``fig`` (Agg renderer, its own size and dpi) and return every text the drawing
    painted, with its box and, for a table cell, the cell's box, in points.

    Only texts that are drawn count: hidden ones, empty strings, tick labels outside the view.
    The figure's canvas is restored afterwards, so it can still be saved to any format.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    old = fig.canvas
    canvas = FigureCanvasAgg(fig)
    painted: dict[int, Text] = {}
    calls = [0]
    try:
        renderer = canvas.get_renderer()
        draw_text, text_draw = renderer.draw_text, Text.draw

        def count(*args, **kwargs):
            calls[0] += 1
            return draw_text(*args, **kwargs)

        def record(self: Text, rend) -> None:
            # a text is painted when its draw reaches the renderer's draw_text (a multi-line
            # text calls it once a line, without naming itself)
            before = calls[0]
            text_draw(self, rend)
            if rend is renderer and calls[0] > before:
                painted[id(self)] = self

        renderer.draw_text = count
        Text.draw = record
        try:
            fig.draw(renderer)
        finally:
            Text.draw = text_draw
            del renderer.draw_text
        scale = 72.0 / fig.dpi
        cells = _cells(fig)
        out = []
        for key, t in painted.items():
            s = t.get_text()
            if not s.strip():
                continue
            b = t.get_window_extent(renderer)
            c = cells.get(key)
            out.append(TextBox(s, tuple(float(v) * scale for v in b.extents),
                               None if c is None else tuple(float(v) * scale
                                                            for v in c.extents)))
        return out
    finally:
        fig.set_canvas(old)


def layout_problems(fig: Figure, *, tolerance: float = TOLERANCE_PT,
                    page: str = "") -> list[LayoutProblem]:
    """Texts of ``fig`` drawn over each other, crossing the page's edge, or overflowing their
    table cell.

    Parameters
    ----------
    fig
        The page, complete (title and footer drawn).
    tolerance
        Overlaps and overhangs up to this many points are ignored.
    page
        Name of the page, carried into each problem.

    Returns
    -------
    list of LayoutProblem
        Empty for a clean page.
    """
    boxes = text_boxes(fig)
    w, h = (float(v) * 72.0 for v in fig.get_size_inches())
    out: list[LayoutProblem] = []
    for tb in boxes:
        x0, y0, x1, y1 = tb.box
        over = max(-x0, -y0, x1 - w, y1 - h)
        if over > tolerance:
            out.append(LayoutProblem("off page", (tb.text,), over, page))
        if tb.cell is not None:
            cx0, cy0, cx1, cy1 = tb.cell
            over = max(cx0 - x0, cy0 - y0, x1 - cx1, y1 - cy1)
            if over > tolerance:
                out.append(LayoutProblem("cell", (tb.text,), over, page))
    if len(boxes) > 1:
        e = np.array([tb.box for tb in boxes])
        dx = np.minimum(e[:, None, 2], e[None, :, 2]) - np.maximum(e[:, None, 0], e[None, :, 0])
        dy = np.minimum(e[:, None, 3], e[None, :, 3]) - np.maximum(e[:, None, 1], e[None, :, 1])
        hit = (dx > tolerance) & (dy > tolerance)
        for i, j in zip(*np.nonzero(np.triu(hit, 1)), strict=True):
            out.append(LayoutProblem("overlap", (boxes[i].text, boxes[j].text),
                                     float(min(dx[i, j], dy[i, j])), page))
    return out


#: Called with (page title, figure) for every page :func:`write_pages` draws, before saving.
page_observers: list = []


@contextlib.contextmanager
def watch_pages(*, tolerance: float = TOLERANCE_PT) -> Iterator[list[LayoutProblem]]:
    """Check every page written inside the ``with`` block; yields the list the problems are
    appended to (each names its page)."""
    found: list[LayoutProblem] = []

    def observe(title: str, fig: Figure) -> None:
        found.extend(layout_problems(fig, tolerance=tolerance, page=title))

    page_observers.append(observe)
    try:
        yield found
    finally:
        page_observers.remove(observe)
