"""Page geometry and the page skeleton: a page is a title and a function drawing on a figure."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from matplotlib.figure import Figure

__all__ = ["PAGE_SIZE", "TABLE_ROWS_PER_PAGE", "CHART_GROUPS_PER_PAGE", "BUDGET_GROUPS_PER_PAGE",
           "RASTER_DPI", "write_pages", "Page", "text_lines", "paginate"]

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


def text_lines(fig: Figure, lines: Sequence[tuple[str, str]], *, top: float = 0.9,
                left: float = 0.05, size: float = 9.0) -> None:
    """Lines of (style, text); style 'h' heading, 'm' monospace, 't' text, '' blank."""
    y = top
    step = size * 1.45 / 72 / PAGE_SIZE[1]
    for style, txt in lines:
        if style == "h":
            y -= 0.4 * step
            fig.text(left, y, txt, fontsize=size + 2, fontweight="bold", va="top")
            y -= 1.25 * step
        elif style == "m":
            fig.text(left + 0.01, y, txt, fontsize=size - 1, family=_MONO, va="top")
            y -= 0.95 * step
        else:
            fig.text(left, y, txt, fontsize=size, va="top")
            y -= step


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


def write_pages(pages: Sequence[Page], path, *, footer: str, meta: dict[str, str]):
    """Draw ``pages`` into the PDF ``path``, written atomically: each titled page with its
    title, ``footer`` and "page i / n"; an untitled page (a title page) with its number only."""
    from matplotlib.backends.backend_pdf import PdfPages

    from ..io.atomic import write_with

    def write(tmp) -> None:
        with PdfPages(tmp, metadata=meta) as pdf:
            for i, page in enumerate(pages, start=1):
                fig = _new_page()
                page.build(fig)
                if page.title:
                    _decorate(fig, page.title, footer, i, len(pages))
                else:
                    fig.text(0.96, 0.02, f"page {i} / {len(pages)}", fontsize=7, color="0.4",
                             ha="right")
                pdf.savefig(fig, dpi=RASTER_DPI)

    return write_with(write, path, suffix=".pdf")
