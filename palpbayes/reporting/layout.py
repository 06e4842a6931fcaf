"""Page geometry and the page skeleton: a page is a title and a function drawing on a figure."""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from matplotlib.figure import Figure

__all__ = ["PAGE_SIZE", "TABLE_ROWS_PER_PAGE", "CHART_GROUPS_PER_PAGE", "BUDGET_GROUPS_PER_PAGE",
           "RASTER_DPI", "write_pages", "Page", "text_lines", "text_height", "text_width",
           "wrap_to", "line_step", "paginate", "thin_ticks", "fit_text_lines"]

#: Resolution [dpi] of the rasterized parts (dense scatter, walker traces); text, axes,
#: curves and bands stay vector graphics.
RASTER_DPI = 110
#: Page size [in]: A4 landscape.
PAGE_SIZE = (11.69, 8.27)
_MONO = "DejaVu Sans Mono"
#: Rows of a table page at most (summary, diagnostics, budget, ...): longer tables continue
#: on further pages, and the charts beside them are split the same way.
TABLE_ROWS_PER_PAGE = 15
#: Material × tip groups drawn at most in one comparison chart.
CHART_GROUPS_PER_PAGE = 12
#: Groups per uncertainty-budget page (its table and its chart share the page).
BUDGET_GROUPS_PER_PAGE = 10


@dataclass
class Page:
    title: str
    build: Callable[[Figure], None]
    #: Most rows of any table (or groups of a chart) drawn on the page (0: none).
    rows: int = 0


def _new_page() -> Figure:
    return Figure(figsize=PAGE_SIZE)


def _decorate(fig: Figure, title: str, footer: str, number: int, total: int) -> None:
    fig.text(0.04, 0.955, title, fontsize=15, fontweight="bold", va="baseline")
    fig.text(0.04, 0.02, footer, fontsize=7, color="0.4")
    fig.text(0.96, 0.02, f"page {number} / {total}", fontsize=7, color="0.4", ha="right")


def text_width(text: str, size: float, *, weight: str = "normal",
               family: str | None = None) -> float:
    """Width of one line of ``text`` at ``size`` points as drawn [points]."""
    from matplotlib.font_manager import FontProperties

    if not text:
        return 0.0
    prop = FontProperties(size=size, weight=weight, family=family)
    w, _, _ = _measurer().get_text_width_height_descent(text, prop, ismath=False)
    return float(w)


@functools.cache
def _measurer():
    """An Agg renderer at 72 dpi: its pixels are points."""
    from matplotlib.backends.backend_agg import RendererAgg

    return RendererAgg(8, 8, 72)


def wrap_to(text: str, width_pt: float, size: float, *, weight: str = "normal",
            family: str | None = None, indent: str = "") -> list[str]:
    """``text`` wrapped into lines no wider than ``width_pt`` points at ``size`` (measured, not
    counted in characters); a newline starts a new line, a word wider than the line stands
    alone.  Lines after the first of a paragraph begin with ``indent``."""
    out: list[str] = []
    for para in str(text).split("\n"):
        words = para.split(" ")
        line = ""
        for word in words:
            trial = word if not line else f"{line} {word}"
            if line and text_width(trial, size, weight=weight, family=family) > width_pt:
                out.append(line)
                line = indent + word
            else:
                line = trial
        out.append(line)
    return out


def line_step(size: float) -> float:
    """Height of one text line of :func:`text_lines` at ``size`` points [figure fraction]."""
    return size * 1.45 / 72 / PAGE_SIZE[1]


def _placed(lines: Sequence[tuple[str, str]], avail: float, size: float
            ) -> tuple[list[tuple[float, float, str, dict]], float]:
    """Where :func:`text_lines` puts each line of ``lines`` (wrapped to ``avail`` points):
    (drop below the top, indent [figure fraction], text, its font keywords) per drawn line,
    and the height below the last one [figure fraction]."""
    step = line_step(size)
    y, out = 0.0, []
    for style, txt in lines:
        if style == "h":
            y += 0.4 * step
            for ln in wrap_to(txt, avail, size + 2, weight="bold"):
                out.append((y, 0.0, ln, {"fontsize": size + 2, "fontweight": "bold"}))
                y += 1.25 * step
        elif style == "m":
            out.append((y, 0.01, txt, {"fontsize": size - 1, "family": _MONO}))
            y += 0.95 * step
        else:
            indent = "   " if txt.startswith("• ") else ""
            for ln in wrap_to(txt, avail, size, indent=indent) if txt else [""]:
                out.append((y, 0.0, ln, {"fontsize": size}))
                y += step
    return out, y


def text_lines(fig: Figure, lines: Sequence[tuple[str, str]], *, top: float = 0.9,
               left: float = 0.05, size: float = 9.0, width: float | None = None) -> float:
    """Lines of (style, text); style 'h' heading, 'm' monospace, 't' text, '' blank.

    Text and heading lines wider than ``width`` (figure fraction; default: to 0.03 from the
    page's right edge) are wrapped there, measured at their font, so that a paragraph may be
    given as one line.  Returns the height below the last line [figure fraction].
    """
    avail = (width if width is not None else 0.97 - left) * fig.get_figwidth() * 72
    placed, height = _placed(lines, avail, size)
    for drop, dx, ln, font in placed:
        fig.text(left + dx, top - drop, ln, va="top", **font)
    return top - height


def text_height(lines: Sequence[tuple[str, str]], *, size: float = 9.0, left: float = 0.05,
                width: float | None = None) -> float:
    """Height :func:`text_lines` takes for ``lines`` on a page [figure fraction] (wrapped
    alike: the same placement, :func:`_placed`)."""
    avail = (width if width is not None else 0.97 - left) * PAGE_SIZE[0] * 72
    return _placed(lines, avail, size)[1]


def fit_text_lines(fig: Figure, lines: Sequence[tuple[str, str]], *, top: float,
                   bottom: float, left: float = 0.05, width: float | None = None,
                   size: float = 9.0, min_size: float = 7.0) -> float:
    """:func:`text_lines` at the largest size from ``size`` down to ``min_size`` (half-point
    steps) at which ``lines`` end above ``bottom``; returns the height below the last line."""
    while size > min_size and top - text_height(lines, size=size, left=left,
                                                width=width) < bottom:
        size -= 0.5
    return text_lines(fig, lines, top=top, left=left, size=size, width=width)


def paginate(lines: list[tuple[str, str]], per_page: float) -> list[list[tuple[str, str]]]:
    """Split lines into pages of at most ``per_page`` line heights, keeping each heading with
    its paragraph unless the paragraph alone is longer than a page."""
    def cost(item: tuple[str, str]) -> float:
        return {"h": 1.65, "m": 0.95}.get(item[0], 1.0)

    blocks: list[list[tuple[str, str]]] = []
    for item in lines:
        if item[0] == "h" or not blocks:
            blocks.append([])
        blocks[-1].append(item)
    pages: list[list[tuple[str, str]]] = []
    cur: list[tuple[str, str]] = []
    used = 0.0
    for block in blocks:
        size = sum(map(cost, block))
        if cur and used + size > per_page:
            pages.append(cur)
            cur, used = [], 0.0
        for item in block:
            if cur and used + cost(item) > per_page:
                pages.append(cur)
                cur, used = [], 0.0
            cur.append(item)
            used += cost(item)
    if cur:
        pages.append(cur)
    return pages


def _draw(fig: Figure):
    """Draw ``fig`` with the Agg renderer (its canvas restored after); return the renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    old = fig.canvas
    try:
        renderer = FigureCanvasAgg(fig).get_renderer()
        fig.draw(renderer)
        return renderer
    finally:
        fig.set_canvas(old)


def _tick_renderer(fig: Figure):
    """An Agg renderer with every axis' ticks and tick labels laid out, as :func:`_draw` would
    leave them, without drawing the figure (a quarter of a page's drawing time): a figure
    with a layout engine, whose axes move at draw time, is drawn."""
    if fig.get_layout_engine() is not None:
        return _draw(fig)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    old = fig.canvas
    try:
        renderer = FigureCanvasAgg(fig).get_renderer()
        for ax in fig.get_axes():
            for axis in (ax.xaxis, ax.yaxis):
                axis.get_tightbbox(renderer)  # updates the ticks and their labels
        return renderer
    finally:
        fig.set_canvas(old)


def _crowded(axis, renderer) -> bool:
    """Whether neighbouring tick labels of ``axis`` run into each other (1 pt apart at
    least)."""
    ax = axis.axes
    lim = ax.get_window_extent(renderer)
    boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels()
             if t.get_visible() and t.get_text()]
    if axis.axis_name == "x":
        spans = sorted((b.x0, b.x1) for b in boxes if lim.x0 - 1 <= 0.5 * (b.x0 + b.x1)
                       <= lim.x1 + 1)
    else:
        spans = sorted((b.y0, b.y1) for b in boxes if lim.y0 - 1 <= 0.5 * (b.y0 + b.y1)
                       <= lim.y1 + 1)
    gap = 1.0 * renderer.points_to_pixels(1.0)
    return any(a[1] + gap > b[0] for a, b in zip(spans[:-1], spans[1:], strict=True))


def thin_ticks(fig: Figure, *, rounds: int = 3) -> None:
    """Fewer ticks on every linear axis of ``fig`` whose tick labels run into each other
    (long labels on a narrow panel: '−0.025  −0.020 ...'), until they stand apart."""
    from matplotlib.ticker import AutoLocator, MaxNLocator

    for _ in range(rounds):
        renderer = _tick_renderer(fig)
        changed = False
        for ax in fig.get_axes():
            for axis in (ax.xaxis, ax.yaxis):
                if axis.get_scale() != "linear" or not _crowded(axis, renderer):
                    continue
                loc = axis.get_major_locator()
                if not isinstance(loc, AutoLocator | MaxNLocator):
                    continue
                n = len([t for t in axis.get_ticklabels() if t.get_text()])
                axis.set_major_locator(MaxNLocator(nbins=max(2, n // 2), steps=[1, 2, 2.5, 5,
                                                                                   10]))
                changed = True
        if not changed:
            return


def write_pages(pages: Sequence[Page], path, *, footer: str, meta: dict[str, str]):
    """Draw ``pages`` into the PDF ``path``, written atomically: each titled page with its
    title, ``footer`` and "page i / n"; an untitled page (a title page) with its number only.

    Each finished page is shown to the callables in
    :data:`palpbayes.reporting.layout_check.page_observers` before it is saved (the layout
    check, :func:`~palpbayes.reporting.layout_check.watch_pages`)."""
    from matplotlib.backends.backend_pdf import PdfPages

    from ..io.atomic import write_with
    from .layout_check import page_observers

    def write(tmp) -> None:
        with PdfPages(tmp, metadata=meta) as pdf:
            for i, page in enumerate(pages, start=1):
                fig = _new_page()
                page.build(fig)
                thin_ticks(fig)
                if page.title:
                    _decorate(fig, page.title, footer, i, len(pages))
                else:
                    fig.text(0.96, 0.02, f"page {i} / {len(pages)}", fontsize=7, color="0.4",
                             ha="right")
                for observe in page_observers:
                    observe(f"page {i}: {page.title or 'title page'}", fig)
                pdf.savefig(fig, dpi=RASTER_DPI)

    return write_with(write, path, suffix=".pdf")
