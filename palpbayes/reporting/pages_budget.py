"""The uncertainty budget pages (table and chart share a page)."""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder
from .layout import BUDGET_GROUPS_PER_PAGE, Page
from .tables import continued, draw_table, page_chunks


def budget_pages(res: ResultsFolder) -> list[Page]:
    bud = res.budget
    if bud is None or bud.empty:
        return []
    inputs = list(dict.fromkeys(bud["input"].astype(str)))
    dist = bud.drop_duplicates("input").set_index("input")["distribution"].astype(str)
    keys = [c for c in ("material", "tip") if c in bud.columns]
    rows, members = [], []
    for key, g in bud.groupby(keys, sort=False) if keys else [((), bud)]:
        key = key if isinstance(key, tuple) else (key,)
        r = {k.capitalize(): str(v) for k, v in zip(keys, key, strict=True)}
        gi = g.set_index("input")
        for name in inputs:
            if name in gi.index:
                r[name] = (f"{float(gi.loc[name, 'share_pct']):.1f} % "
                           f"({float(gi.loc[name, 'rel_sd_pct']):.2g})")
            else:
                r[name] = "–"
        rows.append(r)
        members.append(g.index)
    tab = pd.DataFrame(rows)
    dtab = pd.DataFrame({"Input": inputs, "Distribution": [dist.get(i, "") for i in inputs]})
    chunks = page_chunks(len(tab), BUDGET_GROUPS_PER_PAGE)  # table and chart share the page
    per = max(c.stop - c.start for c in chunks)
    row_h = 0.036
    hgt = row_h * (per + 1)  # the same table height on every page: charts line up
    pages = []
    for k, sl in enumerate(chunks):
        part = tab.iloc[sl]
        idx = [i for m in members[sl] for i in m]
        bpart = bud.loc[idx]

        def build(fig: Figure, part: pd.DataFrame = part, bpart: pd.DataFrame = bpart) -> None:
            h = row_h * (len(part) + 1)
            ax = fig.add_axes((0.03, 0.88 - h, 0.58, h))
            h1 = draw_table(ax, part, fontsize=7.5, row_height=1.0 / (len(part) + 1))
            ax2 = fig.add_axes((0.64, 0.88 - row_h * (len(dtab) + 1), 0.34,
                                row_h * (len(dtab) + 1)))
            h2 = draw_table(ax2, dtab, fontsize=7.5, row_height=1.0 / (len(dtab) + 1))
            # the caption under the taller table (rows grow when a cell wraps)
            cap = min(0.885 - hgt - 0.035, 0.88 - max(h1, h2) - 0.01)
            fig.text(0.03, cap, "Cells: share of the variance of ln E "
                     "(relative sd of E from that input, %). Systematic inputs are shared by "
                     "the traces of a group and applied once to the pooled estimate.",
                     fontsize=8, color="0.25", va="top")
            ax3 = fig.add_axes((0.15, 0.1, 0.62, cap - 0.045 - 0.1 - 0.06))
            plots.plot_budget(bpart, ax=ax3)
        pages.append(Page(continued("Uncertainty budget", k, len(chunks)), build,
                           rows=len(part)))
    return pages
