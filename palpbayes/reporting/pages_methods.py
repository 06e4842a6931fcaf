"""The methods pages (text of :mod:`palpbayes.reporting.methods`)."""

from __future__ import annotations

from matplotlib.figure import Figure

from ..campaign.results import ResultsFolder
from .layout import PAGE_SIZE, Page, paginate, text_lines
from .methods import methods_lines
from .tables import continued


def methods_pages(res: ResultsFolder) -> list[Page]:
    lines = methods_lines(res)
    per_page = int((0.9 - 0.07) * PAGE_SIZE[1] * 72 / (9.0 * 1.45))
    chunks = paginate(lines, per_page)
    pages = []
    for k, chunk in enumerate(chunks):
        def build(fig: Figure, chunk=chunk) -> None:
            text_lines(fig, chunk, top=0.9, left=0.04, size=9.0)
        pages.append(Page(continued("Methods", k, len(chunks)), build))
    return pages
