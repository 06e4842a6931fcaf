"""The report's tables: the summary table (strings, units in the headers), the rows it and the
diagnostics draw from, a matplotlib table filling an axes, and the split of long tables and
charts over pages."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from ..campaign.results import MATERIAL_ORDER, TIP_ORDER, ResultsFolder, ordered
from ..io.tabular import parse_bool
from .format import fmt, interval, isnum, kpa, pm, yesno
from .layout import PAGE_SIZE, TABLE_ROWS_PER_PAGE, text_width, wrap_to

__all__ = ["summary_table", "coverage_counts", "GT_COL", "LS_E_COL", "BAYES_E_COL", "BAYES_NEW_COL",
           "INSTRON_COL", "INSTRON_COVER_COL", "HERTZ_COL", "hertz_of_group", "comparison_groups",
           "pooled_of", "flagged_rows",
           "draw_table", "table_layout", "TableLayout", "page_chunks", "continued",
           "material_pages", "CELL_MARGIN_PT",
           "MIN_TABLE_FONT"]

#: Column headers of the comparison-based summary table (units in the headers).
GT_COL = "GT E ± sd [kPa]"
LS_E_COL = "LS E ± sd [kPa]"
BAYES_E_COL = "Bayes material E ± sd [kPa]"
BAYES_NEW_COL = "Bayes new specimen 90 % [kPa]"
HERTZ_COL = "Hertz LS E [kPa] (Δ vs LS)"
#: The specimen's twin: a new specimen's Instron-equivalent reading, like for like with GT.
INSTRON_COL = "Bayes Instron-equiv. 90 % [kPa]"
INSTRON_COVER_COL = "Instron-equiv. covers GT"


def hertz_of_group(results: ResultsFolder, mat: str, tip: str
                    ) -> tuple[float, float, float, int] | None:
    """The paper's Hertz fit of a sphere group from ``summary.csv``'s least-squares rows.

    Returns (mean E_hertz [Pa], its sd over traces [Pa], mean (E_hertz − E)/E of the same
    rows [-], number of traces), or None when the group has no finite ``E_hertz_pa`` (other
    tips; results written before the column existed).
    """
    s = results.summary
    if "E_hertz_pa" not in s:
        return None
    sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
    for method in ("lsq", "bayes"):
        rows = sub[(sub["method"] == method)]
        eh = pd.to_numeric(rows["E_hertz_pa"], errors="coerce")
        ok = eh.notna()
        if ok.any():
            rel = pd.to_numeric(rows.loc[ok, "E_hertz_rel_diff"], errors="coerce")
            sd = float(eh[ok].std(ddof=1)) if ok.sum() > 1 else float("nan")
            return float(eh[ok].mean()), sd, float(rel.mean()), int(ok.sum())
    return None


def summary_table(results: ResultsFolder) -> pd.DataFrame:
    """The report's summary table (strings; units in the column headers), one row per
    material × tip.

    From ``comparison.csv`` when present: ground truth, least squares E ± sd (mean ± sd over
    the traces) and Bayes' pooled *material* modulus (median ± sd), each method's relative
    error and whether its interval for a *new specimen* covers the ground truth, that interval,
    and the paper's robot numbers with the paper's own error.  When some group is a sphere with
    the paper's Hertz fit recorded (``summary.csv`` ``E_hertz_pa``), a column gives its
    mean over the traces and its difference from the least-squares (Sneddon) E.  Without
    ``comparison.csv``, per-group means of the per-trace estimates of ``summary.csv``.
    """
    comp = results.comparison
    rows = []
    if comp is not None and not comp.empty:
        groups = comparison_groups(comp)
        hertz = {g: hertz_of_group(results, *g) for g in groups}
        for mat, tip in groups:
            sub = comp[(comp["material"].astype(str) == mat) & (comp["tip"].astype(str) == tip)]
            by = {str(r["method"]): r for _, r in sub.iterrows()}
            any_row = sub.iloc[0]
            lsq, bay = by.get("lsq"), by.get("bayes")
            row = {
                "Material": mat, "Tip": tip,
                "n": str(int(any_row["n_traces"])) if isnum(any_row.get("n_traces")) else "–",
                GT_COL: pm(any_row.get("gt_E_pa"), any_row.get("gt_sd_pa")),
            }
            for label, r, e_col, new_col in (
                    ("LS", lsq, LS_E_COL, "LS new specimen 90 % [kPa]"),
                    ("Bayes", bay, BAYES_E_COL, BAYES_NEW_COL)):
                row[e_col] = "–" if r is None else pm(r["E_pa"], r["E_sd_pa"])
                row[new_col] = "–" if r is None else interval(
                    r.get("E_new_lo_pa"), r.get("E_new_hi_pa"))
                row[f"{label} err [%]"] = "–" if r is None else fmt(r.get("rel_err_pct"))
                row[f"{label} covers GT"] = ("–" if r is None
                                             else yesno(r.get("gt_in_new_interval")))
            if bay is not None and isnum(bay.get("E_instron_new_lo_pa")):
                row[INSTRON_COL] = interval(bay.get("E_instron_new_lo_pa"),
                                            bay.get("E_instron_new_hi_pa"))
                row[INSTRON_COVER_COL] = yesno(bay.get("gt_in_instron_interval"))
            row["Paper E ± sd [kPa]"] = pm(any_row.get("paper_E_pa"),
                                            any_row.get("paper_sd_pa"))
            row["Paper err [%] (vs paper's GT)"] = fmt(any_row.get("paper_err_pct"))
            if any(h is not None for h in hertz.values()):
                h = hertz[(mat, tip)]
                row[HERTZ_COL] = "–"
                if h is not None:  # Δ: mean per-trace (E_hertz − E)/E, as on the group page
                    row[HERTZ_COL] = f"{kpa(h[0])} ({100 * h[2]:+.1f} %)"
            if bay is not None and not parse_bool(bay.get("converged_all")):
                row[BAYES_E_COL] += " (!)"
            rows.append(row)
        return pd.DataFrame(rows)
    s = results.summary
    for mat, tip in results.groups():
        sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
        row = {"Material": mat, "Tip": tip, "n": str(sub["trace_id"].nunique())}
        for label, m in (("LS", "lsq"), ("Bayes", "bayes")):
            e = sub.loc[sub["method"] == m, "E_pa"].astype(float)
            row[f"{label} mean E ± sd over traces [kPa]"] = pm(e.mean(), e.std(ddof=1)) \
                if len(e) else "–"
        rows.append(row)
    return pd.DataFrame(rows)


def coverage_counts(results: ResultsFolder) -> dict[str, tuple[int, int]]:
    """Per method, (groups whose new-specimen interval covers the ground truth, groups with a
    ground truth), from ``comparison.csv`` ({} without it); under ``"instron"`` the Bayesian
    groups whose Instron-equivalent interval covers it (the specimen's twin: like for like)."""
    comp = results.comparison
    out: dict[str, tuple[int, int]] = {}
    if comp is None or comp.empty or "gt_in_new_interval" not in comp:
        return out
    for method in ("bayes", "lsq"):
        sub = comp[(comp["method"] == method)]
        if "gt_E_pa" in sub:
            sub = sub[pd.to_numeric(sub["gt_E_pa"], errors="coerce").notna()]
        if len(sub):
            out[method] = (int(sub["gt_in_new_interval"].map(parse_bool).sum()), int(len(sub)))
    if "gt_in_instron_interval" in comp:
        sub = comp[(comp["method"] == "bayes")
                   & pd.to_numeric(comp["E_instron_pa"], errors="coerce").notna()]
        if "gt_E_pa" in sub:
            sub = sub[pd.to_numeric(sub["gt_E_pa"], errors="coerce").notna()]
        if len(sub):
            out["instron"] = (int(sub["gt_in_instron_interval"].map(parse_bool).sum()),
                              int(len(sub)))
    return out


def comparison_groups(comp: pd.DataFrame) -> list[tuple[str, str]]:
    mats = ordered(comp["material"].astype(str), MATERIAL_ORDER)
    tips = ordered(comp["tip"].astype(str), TIP_ORDER)
    have = set(zip(comp["material"].astype(str), comp["tip"].astype(str), strict=True))
    return [(m, t) for m in mats for t in tips if (m, t) in have]


def pooled_of(res: ResultsFolder, mat: str, tip: str) -> pd.Series | None:
    p = res.pooled
    if p is None:
        return None
    sub = p[(p["material"].astype(str) == mat) & (p["tip"].astype(str) == tip)]
    return None if sub.empty else sub.iloc[0]


def flagged_rows(res: ResultsFolder) -> pd.DataFrame:
    b = res.bayes_rows().copy()
    level = (b["flag_level"].fillna("").astype(str) if "flag_level" in b
             else pd.Series("", index=b.index))
    # information ('info: ...', e.g. a base the data cannot tell) is no failure
    real = level == "warning"
    bad = ~b["converged"].map(parse_bool) | real
    return b[bad]


# ----------------------------------------------------------------------------- drawing, pages


#: Space between a cell's text and its border, each side [points].
CELL_MARGIN_PT = 3.0
#: Tables shrink their font down to this size [points] before they wrap cells.
MIN_TABLE_FONT = 6.0


def _col_widths(heads: list[str], text: list[list[str]], size: float) -> list[float]:
    """Each column's natural width at ``size``: its widest header line (bold) or cell line,
    with the margins [points]."""
    out = []
    for j, h in enumerate(heads):
        w = [text_width(x, size, weight="bold") for x in h.split("\n")]
        w += [text_width(x, size) for r in text for x in r[j].split("\n")]
        out.append(max(w) + 2 * CELL_MARGIN_PT)
    return out


def _share(natural: list[float], least: list[float], total: float) -> list[float]:
    """Column widths summing to ``total``: every column its natural width when they fit;
    otherwise the narrow columns keep theirs and the wide ones share what is left, each at
    least its ``least`` width."""
    nat = np.asarray(natural, dtype=float)
    if nat.sum() <= total:
        return list(nat * total / nat.sum())
    low = np.asarray(least, dtype=float)
    fixed = np.zeros(len(nat), dtype=bool)
    w = nat.copy()
    for _ in range(len(nat)):
        free = total - w[fixed].sum()
        share = free * nat[~fixed] / nat[~fixed].sum()
        w[~fixed] = np.maximum(share, low[~fixed])
        newly = (~fixed) & (nat <= w)
        w[newly] = nat[newly]
        if not newly.any() and w.sum() <= total + 1e-9:
            break
        fixed |= newly | ((~fixed) & (w <= low))
        if fixed.all():
            break
    return list(w)


@dataclass
class TableLayout:
    """Where :func:`draw_table` puts a table's text (every size in points).

    Attributes
    ----------
    fontsize
        The font, shrunk from the one asked for when the columns did not fit.
    widths
        Each column's width.
    heads, cells
        The header and the cells' text, wrapped to their columns.
    heights
        Each row's height, the header's first.
    """

    fontsize: float
    widths: list[float]
    heads: list[str]
    cells: list[list[str]]
    heights: list[float]

    @property
    def height(self) -> float:
        return float(sum(self.heights))


def table_layout(df: pd.DataFrame, width: float, *, fontsize: float = 8.0,
                 one_row: float = 0.0, col_weights: Sequence[float] | None = None,
                 wrap_header: int | None = None,
                 min_fontsize: float = MIN_TABLE_FONT) -> TableLayout:
    """The layout of ``df`` as a table ``width`` points wide (see :func:`draw_table`); a row
    of one line is ``one_row`` points high, or what the font needs if more."""
    cols = [str(c) for c in df.columns]
    heads = ["\n".join(textwrap.wrap(c, wrap_header) or [c]) if wrap_header else c
             for c in cols]
    text = [[str(v) for v in row] for row in df.itertuples(index=False)] or [[""] * len(cols)]
    size = fontsize
    natural = _col_widths(heads, text, size)
    while sum(natural) > width and size > min_fontsize:
        size = max(min_fontsize, size - 0.25)
        natural = _col_widths(heads, text, size)
    if col_weights is not None:
        w = np.asarray(col_weights, dtype=float)
        widths = list(w / w.sum() * width)
    else:
        words = [max([text_width(x, size, weight="bold") for x in heads[j].split()]
                     + [text_width(x, size) for r in text for x in r[j].split()] + [0.0])
                 + 2 * CELL_MARGIN_PT for j in range(len(cols))]
        widths = _share(natural, words, width)
    for r in text:  # wrap what does not fit its column
        for j, cell in enumerate(r):
            room = widths[j] - 2 * CELL_MARGIN_PT
            if any(text_width(x, size) > room for x in cell.split("\n")):
                r[j] = "\n".join(wrap_to(cell, room, size))
    heads = ["\n".join(ln for x in h.split("\n")
                       for ln in wrap_to(x, widths[j] - 2 * CELL_MARGIN_PT, size,
                                         weight="bold"))
             for j, h in enumerate(heads)]
    one = max(one_row, 1.6 * size)
    head_lines = max(x.count("\n") + 1 for x in heads)
    heights = [max(one, (1.25 * head_lines + 0.9) * size)]
    heights += [one + 1.2 * size * max(c.count("\n") for c in r) for r in text]
    return TableLayout(size, widths, heads, text, heights)


def draw_table(ax: Axes, df: pd.DataFrame, *, fontsize: float = 8.0,
               highlight: Callable[[int, str, str], str | None] | None = None,
               col_weights: Sequence[float] | None = None, row_height: float | None = None,
               wrap_header: int | None = None, left: Sequence[str] = (),
               min_fontsize: float = MIN_TABLE_FONT) -> float:
    """A real table (matplotlib ``table``) filling ``ax``'s width from its top, header shaded.

    Every cell's text fits its cell.  Column widths follow the widest text of each column
    (measured at the font; ``col_weights`` instead fixes their proportions); when the natural
    widths exceed the axes, the font shrinks, down to ``min_fontsize``, and then the widest
    columns wrap their cells at spaces onto more lines (an interval '872.9 [857.6, 887.2]'
    becomes two lines), the row growing to hold them.  ``wrap_header``: wrap the headers to
    lines of this many characters first; the header row grows to fit them.  ``left``: columns
    whose text is left-aligned (long notes).  ``highlight(row, column, text)`` may return a
    cell colour (``column`` is the unwrapped header, ``text`` the unwrapped cell).

    Returns
    -------
    float
        The table's height [figure fraction]: a row of one line is ``row_height`` (a fraction
        of the axes' height; default min(1/rows, 0.06)) or the font's need if more, a row of
        k lines k − 1 lines taller (:func:`table_layout`).
    """
    ax.set_axis_off()
    cols = [str(c) for c in df.columns]
    fig = ax.figure
    fig_w, fig_h = (fig.get_size_inches() if fig is not None else PAGE_SIZE)
    pos = ax.get_position()
    ax_w, ax_h = fig_w * pos.width * 72.0, fig_h * pos.height * 72.0
    n = len(df) + 1
    lay = table_layout(df, ax_w, fontsize=fontsize,
                       one_row=(row_height if row_height is not None
                                else min(1.0 / n, 0.06)) * ax_h,
                       col_weights=col_weights, wrap_header=wrap_header,
                       min_fontsize=min_fontsize)
    total = lay.height
    tab = ax.table(cellText=lay.cells, colLabels=lay.heads,
                   colWidths=[x / ax_w for x in lay.widths], cellLoc="center", colLoc="center",
                   bbox=[0.0, 1.0 - total / ax_h, 1.0, total / ax_h])
    tab.auto_set_font_size(False)
    tab.set_fontsize(lay.fontsize)
    lefts = {cols.index(c) for c in left if c in cols}
    for (r, c), cell in tab.get_celld().items():
        cell.set_edgecolor("0.75")
        cell.set_linewidth(0.5)
        cell.PAD = CELL_MARGIN_PT / lay.widths[c]
        cell.set_height(lay.heights[r] / ax_h)
        if c in lefts and r > 0:
            cell.set_text_props(ha="left")
        if r == 0:
            cell.set_facecolor("#e8eef4")
            cell.get_text().set_fontweight("bold")
        elif r % 2 == 0:
            cell.set_facecolor("#f7f7f7")
        if r > 0 and highlight is not None and r - 1 < len(df):
            color = highlight(r - 1, cols[c], str(df.iat[r - 1, c]))
            if color:
                cell.set_facecolor(color)
    return total / 72.0 / fig_h


def page_chunks(n: int, per_page: int = 0) -> list[slice]:
    """Slices of ``n`` rows into pages of at most ``per_page`` (default
    :data:`TABLE_ROWS_PER_PAGE`) rows, balanced (27 rows at 15 → 14 + 13); [slice(0, 0)] for
    none."""
    per_page = per_page or TABLE_ROWS_PER_PAGE
    k = max(1, math.ceil(n / per_page))
    bounds = np.linspace(0, n, k + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def continued(title: str, k: int, n: int) -> str:
    """Title of page ``k`` (0-based) of ``n``: the first as is, then 'title (continued, 2/3)'."""
    return title if k == 0 or n <= 1 else f"{title} (continued, {k + 1}/{n})"


def material_pages(groups: Sequence[tuple[str, str]], per_page: int
                    ) -> list[list[tuple[str, str]]]:
    """(material, tip) groups split into pages of at most ``per_page`` groups, keeping a
    material's tips together (a material with more tips than ``per_page`` is split), with as
    few pages as that allows and the groups spread evenly over them."""
    by_mat: dict[str, list[tuple[str, str]]] = {}
    for g in groups:
        by_mat.setdefault(g[0], []).append(g)

    def pack(limit: int) -> list[list[tuple[str, str]]]:
        pages: list[list[tuple[str, str]]] = []
        cur: list[tuple[str, str]] = []
        for gs in by_mat.values():
            if cur and len(cur) + len(gs) > limit:
                pages.append(cur)
                cur = []
            while len(gs) > limit:
                pages.append(gs[:limit])
                gs = gs[limit:]
            cur += gs
        if cur:
            pages.append(cur)
        return pages

    best = pack(per_page)
    for limit in range(math.ceil(len(groups) / max(len(best), 1)), per_page):
        even = pack(limit)
        if len(even) == len(best):
            return even
    return best
