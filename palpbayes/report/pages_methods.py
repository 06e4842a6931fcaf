"""The methods pages (text of :mod:`palpbayes.report.methods`)."""

from __future__ import annotations

from matplotlib.figure import Figure

from ..campaign.results import ResultsFolder
from .layout import PAGE_SIZE, _Page, _paginate, _text_lines
from .methods import _methods_lines
from .tables import _continued


def _pages_methods(res: ResultsFolder) -> list[_Page]:
    lines = _methods_lines(res)
    per_page = int((0.9 - 0.07) * PAGE_SIZE[1] * 72 / (9.0 * 1.45))
    chunks = _paginate(lines, per_page)
    pages = []
    for k, chunk in enumerate(chunks):
        def build(fig: Figure, chunk=chunk) -> None:
            _text_lines(fig, chunk, top=0.9, left=0.04, size=9.0)
        pages.append(_Page(_continued("Methods", k, len(chunks)), build))
    return pages
