"""The report's tables: the summary table (strings, units in the headers), the rows it and the
diagnostics draw from, a matplotlib table filling an axes, and the split of long tables and
charts over pages."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from ..campaign.results import MATERIAL_ORDER, TIP_ORDER, ResultsFolder, ordered
from ..io.tabular import parse_bool
from .format import KPA, fmt, interval, isnum, pm, yesno
from .layout import PAGE_SIZE, TABLE_ROWS_PER_PAGE

__all__ = ["summary_table", "coverage_counts", "GT_COL", "LS_E_COL", "BAYES_E_COL", "BAYES_NEW_COL",
           "INSTRON_COL", "INSTRON_COVER_COL", "HERTZ_COL", "hertz_of_group", "comparison_groups",
           "pooled_of", "flagged_rows",
           "draw_table", "page_chunks", "continued", "material_pages"]

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
                    row[HERTZ_COL] = f"{fmt(h[0] * KPA)} ({100 * h[2]:+.1f} %)"
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


def draw_table(ax: Axes, df: pd.DataFrame, *, fontsize: float = 8.0,
                highlight: Callable[[int, str, str], str | None] | None = None,
                col_weights: Sequence[float] | None = None, row_height: float | None = None,
                wrap_header: int | None = None) -> None:
    """A real table (matplotlib ``table``) filling ``ax`` from the top, header shaded.

    Column widths follow the longest string (or header line) of each column, or
    ``col_weights``.  ``wrap_header``: wrap the headers to lines of this many characters; the
    header row grows to fit them.  ``highlight(row, column, text)`` may return a cell colour
    (``column`` is the unwrapped header).
    """
    ax.set_axis_off()
    cols = [str(c) for c in df.columns]
    heads = ["\n".join(textwrap.wrap(c, wrap_header) or [c]) if wrap_header else c
             for c in cols]
    text = [[str(v) for v in row] for row in df.itertuples(index=False)]
    if col_weights is None:
        # bold header text is ~15 % wider than the cells' regular text
        col_weights = [max([1.15 * len(x) for x in heads[j].split("\n")]
                           + [len(r[j]) for r in text]) + 2 for j in range(len(cols))]
    w = np.asarray(col_weights, dtype=float)
    w = w / w.sum()
    n = len(text) + 1
    h = row_height if row_height is not None else min(1.0 / n, 0.06)
    lines = max(x.count("\n") + 1 for x in heads) if heads else 1
    fig_h = ax.figure.get_size_inches()[1] if ax.figure is not None else PAGE_SIZE[1]
    ax_pt = fig_h * ax.get_position().height * 72.0
    hh = max(h, (1.25 * lines + 0.9) * fontsize / ax_pt) if ax_pt > 0 else h
    total = hh + h * (n - 1)
    tab = ax.table(cellText=text or [[""] * len(cols)], colLabels=heads, colWidths=list(w),
                   cellLoc="center", colLoc="center", bbox=[0.0, 1.0 - total, 1.0, total])
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    for (r, c), cell in tab.get_celld().items():
        cell.set_edgecolor("0.75")
        cell.set_linewidth(0.5)
        cell.PAD = 0.04  # of the cell width, each side (matplotlib's 0.1 wastes a fifth)
        if r == 0:
            cell.set_height(cell.get_height() * hh / h)
            cell.set_facecolor("#e8eef4")
            cell.get_text().set_fontweight("bold")
        elif r % 2 == 0:
            cell.set_facecolor("#f7f7f7")
        if r > 0 and highlight is not None and r - 1 < len(text):
            color = highlight(r - 1, cols[c], text[r - 1][c])
            if color:
                cell.set_facecolor(color)


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
