"""Assembling the report: every page in order, numbered and footed, into one PDF."""

from __future__ import annotations

import datetime as _dt
import os
from dataclasses import dataclass, field
from pathlib import Path

from .. import __version__
from ..campaign.results import ResultsFolder, load_results, load_rheology_table
from ..errors import InputError
from ..io.tabular import parse_bool
from ..outputs import REPORT, RHEOLOGY_TABLE, SUMMARY
from .format import shown_path
from .layout import RASTER_DPI, Page, write_pages
from .pages_budget import budget_pages
from .pages_diagnostics import diagnostics_page
from .pages_group import group_page
from .pages_layer import layer_pages
from .pages_methods import methods_pages
from .pages_online import online_pages
from .pages_rheology import rheology_pages, rheology_title_page, row_failed
from .pages_stiffening import stiffening_groups, stiffening_page, stiffening_table_pages
from .pages_summary import comparison_pages, summary_pages
from .pages_title import title_page
from .pages_twin import twin_pages
from .tables import flagged_rows

__all__ = ["REPORT_NAME", "RASTER_DPI", "ReportInfo", "report"]

#: Default file name of the report inside a results folder.
REPORT_NAME = REPORT


@dataclass
class ReportInfo:
    """What :func:`report` wrote.

    Attributes
    ----------
    path
        The PDF.
    titles
        Page titles in order.
    n_traces
        Traces in the results folder (``summary.csv``'s, else ``rheology.csv``'s).
    n_flagged
        Bayesian fits not converged or with a warning (the diagnostics page's table).
    n_pooled_flagged
        Pooled (hierarchical) groups whose chain did not converge.
    table_rows
        Per page, the most rows of a table (or material × tip groups of a chart) on it; 0 for
        pages without one.  Tables are split at :data:`TABLE_ROWS_PER_PAGE` rows.
    results_shown
        The results folder as printed on the title page and in the footer.
    n_rheology, n_rheology_failed_check
        Viscoelastic fits (fitted rows of ``rheology.csv``) and those whose model check
        failed.
    """

    path: Path
    titles: list[str]
    n_traces: int
    n_flagged: int
    n_pooled_flagged: int = 0
    table_rows: list[int] = field(default_factory=list)
    results_shown: str = ""
    n_rheology: int = 0
    n_rheology_failed_check: int = 0

    @property
    def n_pages(self) -> int:
        return len(self.titles)


def report(results: str | os.PathLike | ResultsFolder, pdf: str | os.PathLike | None = None,
                 *, seed: int = 0, created: str | None = None) -> ReportInfo:
    """Write the PDF report of a results folder (pages listed in :mod:`palpbayes.reporting`).

    A folder with viscoelastic fits (``rheology.csv``, ``palpbayes fit --rheology``) gets their
    pages (:mod:`~palpbayes.reporting.pages_rheology`) before the methods; one with only those is
    reported with a title page and those pages.

    Parameters
    ----------
    results
        Results folder (or one loaded with :func:`load_results`).
    pdf
        Output file (default ``<results>/report.pdf``); written atomically.
    seed
        Seed of the posterior-predictive draws in the plots.
    created
        Date printed on the title page (default: today, ISO format).

    Returns
    -------
    ReportInfo

    Raises
    ------
    InputError
        The folder has neither ``summary.csv`` nor ``rheology.csv``; the output is no PDF.
    """
    folder = results.path if isinstance(results, ResultsFolder) else Path(results)
    out = Path(pdf) if pdf is not None else folder / REPORT_NAME
    if out.suffix.lower() != ".pdf":
        raise InputError(f"{out}: the report is a PDF; give a file name ending in .pdf")
    if not isinstance(results, ResultsFolder) and not folder.is_dir():
        raise InputError(f"{folder}: no such results folder")
    rheo = load_rheology_table(folder)
    created = created or _dt.date.today().isoformat()
    if not isinstance(results, ResultsFolder) and not (folder / SUMMARY).is_file():
        if rheo is None:
            raise InputError(f"{folder}: neither {SUMMARY} ('palpbayes fit') nor "
                             f"{RHEOLOGY_TABLE} ('palpbayes fit --rheology power-law|sls'); "
                             "fit first, or give a campaign folder or manifest to fit it")
        return _rheology_report(folder, rheo, out, created)
    res = results if isinstance(results, ResultsFolder) else load_results(results)
    contents: list[str] = []
    pages: list[Page] = [title_page(res, created, contents), *summary_pages(res)]
    if res.comparison is not None and not res.comparison.empty:
        pages += comparison_pages(res)
    pages += layer_pages(res)
    pages += twin_pages(res)
    pages += [group_page(res, m, t, seed) for m, t in res.groups()]
    pages += diagnostics_page(res)
    pages += budget_pages(res)
    pages += [stiffening_page(res, m, t) for m, t in stiffening_groups(res)]
    pages += stiffening_table_pages(res)
    pages += online_pages(res)
    pages += rheology_pages(res.path, rheo)
    pages += methods_pages(res)
    footer = (f"palpbayes {__version__} · campaign {res.name} · {created} · results "
              f"{shown_path(res.path)}")
    titles = [p.title or "palpbayes report" for p in pages]
    contents.extend(titles)

    write_pages(pages, out, footer=footer,
                meta={"Title": f"palpbayes report: {res.name}",
                      "Creator": f"palpbayes {__version__}",
                      "Subject": "Elastic modulus from robotic palpation"})
    b = res.bayes_rows()
    n_pool = 0
    if res.pooled is not None and "converged" in res.pooled:
        n_pool = int((~res.pooled["converged"].map(parse_bool)).sum())
    return ReportInfo(path=out, titles=titles, n_traces=int(res.summary["trace_id"].nunique()),
                      n_flagged=int(len(flagged_rows(res))) if len(b) else 0,
                      n_pooled_flagged=n_pool, table_rows=[p.rows for p in pages],
                      results_shown=shown_path(res.path), **_rheology_counts(rheo))


def _rheology_counts(rheo) -> dict:
    """Viscoelastic fits of ``rheology.csv`` and those whose model check failed."""
    if rheo is None:
        return {}
    fitted = rheo[~rheo.apply(row_failed, axis=1)]
    failed = int((~fitted["model_ok"].map(parse_bool)).sum()) if "model_ok" in fitted else 0
    return {"n_rheology": int(len(fitted)), "n_rheology_failed_check": failed}


def _rheology_report(folder: Path, rheo, out: Path, created: str) -> ReportInfo:
    """The report of a folder with viscoelastic fits only: a title page and their pages."""
    contents: list[str] = []
    pages = [rheology_title_page(folder, rheo, created, contents),
             *rheology_pages(folder, rheo)]
    titles = [p.title or "palpbayes report" for p in pages]
    contents.extend(titles)
    footer = (f"palpbayes {__version__} · viscoelastic fits {folder.resolve().name} · "
              f"{created} · results {shown_path(folder)}")
    write_pages(pages, out, footer=footer,
                meta={"Title": f"palpbayes report: {folder.resolve().name}",
                      "Creator": f"palpbayes {__version__}",
                      "Subject": "Relaxation modulus from palpation"})
    return ReportInfo(path=out, titles=titles, n_traces=int(rheo["trace_id"].nunique()),
                      n_flagged=0, table_rows=[p.rows for p in pages],
                      results_shown=shown_path(folder), **_rheology_counts(rheo))
