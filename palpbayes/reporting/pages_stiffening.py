"""Stiffening pages: E(t) vs rest time per material × tip and ``stiffening.csv``, drawn from
the tables ``palpbayes compare`` wrote (:mod:`palpbayes.campaign.stiffening_tables`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder
from .format import wrap
from .layout import Page, text_lines
from .tables import continued, draw_table, page_chunks

__all__ = ["stiffening_groups", "stiffening_page", "stiffening_table_pages"]


def _of(table: pd.DataFrame, mat: str, tip: str) -> pd.DataFrame:
    return table[(table["material"].astype(str) == mat) & (table["tip"].astype(str) == tip)]


def stiffening_groups(res: ResultsFolder) -> list[tuple[str, str]]:
    """Groups with a stiffening law in the compare step's tables (rows, parameters and
    curve), in the results' group order."""
    tabs = (res.stiffening, res.stiffening_parameters, res.stiffening_curves)
    if any(t is None or t.empty for t in tabs):
        return []
    return [(m, t) for m, t in res.groups() if all(len(_of(x, m, t)) for x in tabs)]


def stiffening_page(res: ResultsFolder, mat: str, tip: str) -> Page:
    """The palpations' E against rest time with the group's law and its band, the law's
    parameters and the verdict (``stiffening*.csv``)."""
    row = _of(res.stiffening, mat, tip).iloc[0]
    params = _of(res.stiffening_parameters, mat, tip)
    curve = _of(res.stiffening_curves, mat, tip)

    def build(fig: Figure) -> None:
        b = res.bayes_rows()
        g = b[(b["material"].astype(str) == mat) & (b["tip"].astype(str) == tip)]
        t = pd.to_numeric(g["rest_time_s"], errors="coerce")
        rows = g[np.isfinite(t)]
        fresh = g[~np.isfinite(t)]
        rested = None
        if len(fresh):
            r = fresh.iloc[0]
            rested = (r["E_stat_pa"], r["E_stat_lo_pa"], r["E_stat_hi_pa"])
        ax = fig.add_axes((0.07, 0.12, 0.5, 0.74))
        plots.plot_stiffening(rows["rest_time_s"].astype(float), rows["E_stat_pa"],
                              E_lo=rows["E_stat_lo_pa"], E_hi=rows["E_stat_hi_pa"],
                              curve_t=curve["t_s"].to_numpy(float),
                              curve_median=curve["median_pa"].to_numpy(float),
                              curve_lo=curve["lo_pa"].to_numpy(float),
                              curve_hi=curve["hi_pa"].to_numpy(float),
                              curve_label=f"fitted {params['law'].iloc[0]}",
                              rested=rested, ax=ax)
        show = pd.DataFrame({"parameter": params["parameter"], "unit": params["unit"],
                             "median": params["median"].map(lambda v: f"{v:.4g}"),
                             "90 % interval": [f"[{a:.4g}, {b:.4g}]"
                                               for a, b in zip(params["lo"], params["hi"],
                                                               strict=True)]})
        ax2 = fig.add_axes((0.62, 0.62, 0.35, 0.24))
        draw_table(ax2, show, fontsize=8, row_height=1.0 / (len(show) + 1))
        lines = [("t", f"Preferred law: {params['law'].iloc[0]}"), ("", "")]
        lines += [("t", ln) for ln in wrap(str(row["message"]), 62)]
        lines += [("", ""), ("t", "Statistical E of each palpation (the budget's systematic "),
                  ("t", "inputs scale the whole curve, not its shape).")]
        text_lines(fig, lines, top=0.56, left=0.62, size=8.5)
    title = f"Stiffening after repeated palpation: {mat} · {tip}" if mat else \
        f"Stiffening after repeated palpation: {tip}"
    return Page(title, build)


def stiffening_table_pages(res: ResultsFolder) -> list[Page]:
    st = res.stiffening
    if st is None or st.empty:
        return []
    cols = [c for c in st.columns if not c.startswith("_")]
    show = st[cols].copy()
    for c in show.columns:
        if pd.api.types.is_float_dtype(show[c]):
            show[c] = show[c].map(lambda v: f"{v:.4g}")
    chunks = page_chunks(len(show))
    per = max(c.stop - c.start for c in chunks)
    pages = []
    for k, sl in enumerate(chunks):
        part = show.iloc[sl]

        def build(fig: Figure, part: pd.DataFrame = part) -> None:
            ax = fig.add_axes((0.03, 0.2, 0.94, 0.68))
            draw_table(ax, part, fontsize=7, row_height=min(0.06, 1.0 / (per + 1)))
        pages.append(Page(continued("Stiffening (stiffening.csv)", k, len(chunks)), build,
                           rows=len(part)))
    return pages
