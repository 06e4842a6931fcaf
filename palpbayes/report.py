"""The PDF report of a results folder: what a researcher attaches to a lab notebook.

:func:`build_report` reads a results folder (:mod:`palpbayes.results`: ``summary.csv``,
``posterior/*.nc``, ``settings.json``, ``traces.csv`` and, when present, ``comparison.csv``,
``pooled.csv``, ``budget.csv``, ``stiffening.csv``, ``groundtruth.csv`` /
``groundtruth_summary.csv``) and writes a multi-page PDF (A4 landscape, written atomically):

1. title page: campaign, date, palpbayes version, the results folder it was built from,
   settings, contents;
2. summary table in the layout of the paper's Table III (units in the headers): ground truth,
   least squares and Bayes E ± sd per material × tip, errors, whether each new-specimen
   interval covers the ground truth (with the overall count), the paper's robot numbers and,
   for spheres, the paper's Hertz fit of the same traces;
3. the same comparison as a figure;
4. one page per material × tip: force-depth data of a representative trace with the
   posterior-predictive band and the least-squares curve, residuals, posterior of E and of
   (E, z_surf), per-trace intervals with the pooled result; sphere pages also state the
   paper's Hertz fit (``summary.csv`` ``E_hertz_pa``) against the exact Sneddon law;
5. convergence diagnostics (every non-converged or flagged fit, or the statement that all
   converged with the largest R-hat and smallest ESS) and the walkers of the worst fit;
6. the uncertainty budget (table and chart);
7. the stiffening law E(t) vs rest time (:mod:`palpbayes.stiffening`) for every material × tip
   whose palpations have at least :data:`STIFFENING_MIN_REST_TIMES` distinct rest times, and
   ``stiffening.csv`` when present;
8. methods: models, priors, noise model, least squares, the sampler's stopping rule (numbers
   from ``settings.json``), pooling (:data:`palpbayes.pooling.POOLING_SETTINGS`, tau prior from
   ``pooled.csv``), ground-truth window.

Tables continue on further pages beyond :data:`TABLE_ROWS_PER_PAGE` rows ('… (continued, 2/3)'),
comparison charts beyond :data:`CHART_GROUPS_PER_PAGE` material × tip groups (whole materials
per page) and budget pages beyond :data:`BUDGET_GROUPS_PER_PAGE` groups, so a campaign of any
size stays readable.

This module only draws: reading a results folder is :mod:`palpbayes.results`, fitting a campaign
first (``palpbayes report CAMPAIGN``) is :func:`palpbayes.pipeline.run_pipeline`.  Both modules'
public names used by notebooks (``load_results``, ``load_fit``, ``ResultsFolder``,
``run_pipeline``, ``example_campaign_dir``) are re-exported here for compatibility.

Matplotlib is used through its object API only (figures are rendered by the PDF backend;
:mod:`matplotlib.pyplot` is never imported), so the report works under any backend.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from . import __version__, plots
from .bayes.sampler import MOVES
from .errors import InputError
from .layout import REPORT, posterior_path
from .pipeline import example_campaign_dir, run_pipeline
from .results import (
    MATERIAL_ORDER,
    TIP_ORDER,
    ResultsFolder,
    load_fit,
    load_results,
    ordered,
)

__all__ = [
    "PAGE_SIZE",
    "REPORT_NAME",
    "RASTER_DPI",
    "STIFFENING_MIN_REST_TIMES",
    "TABLE_ROWS_PER_PAGE",
    "CHART_GROUPS_PER_PAGE",
    "BUDGET_GROUPS_PER_PAGE",
    "MOVES_TEXT",
    "ReportInfo",
    "summary_table",
    "coverage_counts",
    "GT_COL",
    "LS_E_COL",
    "BAYES_E_COL",
    "BAYES_NEW_COL",
    "HERTZ_COL",
    "build_report",
    # re-exported from palpbayes.results and palpbayes.pipeline (notebooks import them here)
    "ResultsFolder",
    "load_results",
    "load_fit",
    "example_campaign_dir",
    "run_pipeline",
]

#: Page size [in]: A4 landscape.
PAGE_SIZE = (11.69, 8.27)
#: Default file name of the report inside a results folder.
REPORT_NAME = REPORT
#: Resolution [dpi] of the rasterized parts (dense scatter, walker traces); text, axes,
#: curves and bands stay vector graphics.
RASTER_DPI = 110

_KPA = 1e-3
_MONO = "DejaVu Sans Mono"
#: A material × tip group gets a stiffening page when it has this many distinct rest times.
STIFFENING_MIN_REST_TIMES = 3
#: Rows of a table page at most (summary, diagnostics, budget, ...): longer tables continue
#: on further pages, and the charts beside them are split the same way.
TABLE_ROWS_PER_PAGE = 15
#: Material × tip groups drawn at most in one comparison chart.
CHART_GROUPS_PER_PAGE = 12
#: Groups per uncertainty-budget page (its table and its chart share the page).
BUDGET_GROUPS_PER_PAGE = 10



# ----------------------------------------------------------------------------- tables


def _fmt(v: Any, digits: int = 1) -> str:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "–"
    return "–" if not math.isfinite(x) else f"{x:.{digits}f}"


def _pm(e: Any, sd: Any, digits: int = 1) -> str:
    a, b = _fmt(float(e) * _KPA if _isnum(e) else e, digits), \
        _fmt(float(sd) * _KPA if _isnum(sd) else sd, digits)
    if a == "–":
        return "–"
    return a if b == "–" else f"{a} ± {b}"


def _isnum(v: Any) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def _yesno(v: Any) -> str:
    if isinstance(v, str):
        v = {"true": True, "false": False}.get(v.strip().lower(), v)
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return "yes" if bool(v) else "NO"


def _interval(lo: Any, hi: Any, digits: int = 0) -> str:
    if not (_isnum(lo) and _isnum(hi)):
        return "–"
    return f"[{float(lo) * _KPA:.{digits}f}, {float(hi) * _KPA:.{digits}f}]"


#: Column headers of the comparison-based summary table (units in the headers).
GT_COL = "GT E ± sd [kPa]"
LS_E_COL = "LS E ± sd [kPa]"
BAYES_E_COL = "Bayes material E ± sd [kPa]"
BAYES_NEW_COL = "Bayes new specimen 90 % [kPa]"
HERTZ_COL = "Hertz LS E [kPa] (Δ vs LS)"


def _hertz_of_group(results: ResultsFolder, mat: str, tip: str
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
        groups = _comparison_groups(comp)
        hertz = {g: _hertz_of_group(results, *g) for g in groups}
        for mat, tip in groups:
            sub = comp[(comp["material"].astype(str) == mat) & (comp["tip"].astype(str) == tip)]
            by = {str(r["method"]): r for _, r in sub.iterrows()}
            any_row = sub.iloc[0]
            lsq, bay = by.get("lsq"), by.get("bayes")
            row = {
                "Material": mat, "Tip": tip,
                "n": str(int(any_row["n_traces"])) if _isnum(any_row.get("n_traces")) else "–",
                GT_COL: _pm(any_row.get("gt_E_pa"), any_row.get("gt_sd_pa")),
            }
            for label, r, e_col, new_col in (
                    ("LS", lsq, LS_E_COL, "LS new specimen 90 % [kPa]"),
                    ("Bayes", bay, BAYES_E_COL, BAYES_NEW_COL)):
                row[e_col] = "–" if r is None else _pm(r["E_pa"], r["E_sd_pa"])
                row[new_col] = "–" if r is None else _interval(
                    r.get("E_new_lo_pa"), r.get("E_new_hi_pa"))
                row[f"{label} err [%]"] = "–" if r is None else _fmt(r.get("rel_err_pct"))
                row[f"{label} covers GT"] = "–" if r is None else _yesno(r.get("gt_in_interval"))
            row["Paper E ± sd [kPa]"] = _pm(any_row.get("paper_E_pa"),
                                            any_row.get("paper_sd_pa"))
            row["Paper err [%] (vs paper's GT)"] = _fmt(any_row.get("paper_err_pct"))
            if any(h is not None for h in hertz.values()):
                h = hertz[(mat, tip)]
                row[HERTZ_COL] = "–"
                if h is not None:  # Δ: mean per-trace (E_hertz − E)/E, as on the group page
                    row[HERTZ_COL] = f"{_fmt(h[0] * _KPA)} ({100 * h[2]:+.1f} %)"
            if bay is not None and not _truthy(bay.get("converged_all")):
                row[BAYES_E_COL] += " (!)"
            rows.append(row)
        return pd.DataFrame(rows)
    s = results.summary
    for mat, tip in results.groups():
        sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
        row = {"Material": mat, "Tip": tip, "n": str(sub["trace_id"].nunique())}
        for label, m in (("LS", "lsq"), ("Bayes", "bayes")):
            e = sub.loc[sub["method"] == m, "E_pa"].astype(float)
            row[f"{label} mean E ± sd over traces [kPa]"] = _pm(e.mean(), e.std(ddof=1)) \
                if len(e) else "–"
        rows.append(row)
    return pd.DataFrame(rows)


def coverage_counts(results: ResultsFolder) -> dict[str, tuple[int, int]]:
    """Per method, (groups whose new-specimen interval covers the ground truth, groups with a
    ground truth), from ``comparison.csv`` ({} without it)."""
    comp = results.comparison
    out: dict[str, tuple[int, int]] = {}
    if comp is None or comp.empty or "gt_in_interval" not in comp:
        return out
    for method in ("bayes", "lsq"):
        sub = comp[(comp["method"] == method)]
        if "gt_E_pa" in sub:
            sub = sub[pd.to_numeric(sub["gt_E_pa"], errors="coerce").notna()]
        if len(sub):
            out[method] = (int(sub["gt_in_interval"].map(_truthy).sum()), int(len(sub)))
    return out


def _comparison_groups(comp: pd.DataFrame) -> list[tuple[str, str]]:
    mats = ordered(comp["material"].astype(str), MATERIAL_ORDER)
    tips = ordered(comp["tip"].astype(str), TIP_ORDER)
    have = set(zip(comp["material"].astype(str), comp["tip"].astype(str), strict=True))
    return [(m, t) for m in mats for t in tips if (m, t) in have]


def _draw_table(ax: Axes, df: pd.DataFrame, *, fontsize: float = 8.0,
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


def _chunks(n: int, per_page: int = 0) -> list[slice]:
    """Slices of ``n`` rows into pages of at most ``per_page`` (default
    :data:`TABLE_ROWS_PER_PAGE`) rows, balanced (27 rows at 15 → 14 + 13); [slice(0, 0)] for
    none."""
    per_page = per_page or TABLE_ROWS_PER_PAGE
    k = max(1, math.ceil(n / per_page))
    bounds = np.linspace(0, n, k + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _continued(title: str, k: int, n: int) -> str:
    """Title of page ``k`` (0-based) of ``n``: the first as is, then 'title (continued, 2/3)'."""
    return title if k == 0 or n <= 1 else f"{title} (continued, {k + 1}/{n})"


# ----------------------------------------------------------------------------- pages


@dataclass
class _Page:
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


def _text_lines(fig: Figure, lines: Sequence[tuple[str, str]], *, top: float = 0.9,
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


def _wrap(text: str, width: int) -> list[str]:
    out: list[str] = []
    for para in text.split("\n"):
        # no breaks inside 'R-hat', 'post-burn-in', 'de-snooker'
        out.extend(textwrap.wrap(para, width, break_on_hyphens=False) or [""])
    return out


def _paginate(lines: list[tuple[str, str]], per_page: float) -> list[list[tuple[str, str]]]:
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


def _settings_lines(res: ResultsFolder) -> list[tuple[str, str]]:
    """The fit settings of ``settings.json`` as lines of text."""
    o = res.options
    s = res.settings
    pri = o.get("priors") or {}
    bud = o.get("budget") or {}
    smp, _ = _sampler_settings(o.get("settings"))
    if o.get("thickness_correction"):
        thick = "on (" + ("bonded" if o.get("bonded", True) else "non-bonded") + ")"
    else:
        thick = "off (half-space, as the paper)"
    frac = o.get("fit_fraction")
    if frac is None:
        from .contact import Tip
        from .fitdata import default_fit_fraction

        flat = default_fit_fraction(Tip("flat", radius=1.0))
        frac = f"paper default ({flat:g} flat, 0 others)"
    else:
        frac = f"{frac:g}"
    depth = o.get("max_depth")
    depth = "none" if depth is None else f"{1e3 * float(depth):g} mm"
    nu_b = bud.get("nu_range") or f"nu ± {bud.get('nu_half_width')}"
    n_tr = s.get("n_traces", res.summary["trace_id"].nunique())
    return [
        ("t", f"Methods fitted: {s.get('method', '?')};  base seed: {s.get('seed', '?')};  "
              f"traces: {n_tr}"),
        ("t", f"Contact model: Poisson ratio nu = {o.get('nu')}; finite-thickness correction "
              f"{thick}"),
        ("t", f"Fit window: F_unc = {_fmt(1e3 * float(o.get('f_unc', 0.048)), 0)} mN; fit "
              f"fraction {frac}; max depth {depth}"),
        ("t", f"Noise model: {o.get('noise', 'gaussian')}; sensor noise "
              f"{_fmt(1e3 * float(pri.get('noise_pp', 0.048)), 0)} mN peak-to-peak (sigma "
              "prior centred on pp/6)"),
        ("t", f"Budget: Poisson ratio {nu_b}; tip radius "
              f"±{_fmt(100 * float(bud.get('radius_tolerance', 0)), 1)} %; force gain sd "
              f"{_fmt(100 * float(bud.get('gain_sd', 0)), 1)} %; compliance "
              f"0–{bud.get('compliance_max')} m/N"),
        ("t", f"Sampler: emcee, {smp.get('n_walkers')} walkers, moves '{smp.get('moves')}' "
              f"({MOVES_TEXT.get(str(smp.get('moves')), 'see emcee')}), "
              f"{_range(smp.get('min_steps'), smp.get('max_steps'))} steps, chain longer than "
              f"{float(smp.get('tau_factor')):g}·tau, R-hat and ESS checked before stopping "
              "(the stopping rule in full on the Methods page)"),
    ]


def _page_title(res: ResultsFolder, created: str, contents: list[str]) -> _Page:
    def build(fig: Figure) -> None:
        fig.text(0.5, 0.78, "palpbayes report", ha="center", fontsize=30, fontweight="bold")
        fig.text(0.5, 0.71, f"Campaign: {res.name}", ha="center", fontsize=18)
        fig.text(0.5, 0.66, "Elastic modulus from robotic palpation: least squares vs Bayes, "
                 "compared with compression ground truth", ha="center", fontsize=11,
                 color="0.3")
        fig.text(0.5, 0.62, f"Built from the results folder {_shown(res.path)}", ha="center",
                 fontsize=11, fontweight="bold", color="0.2")
        s = res.settings
        n_tr = res.summary["trace_id"].nunique()
        groups = res.groups()
        info = [
            ("t", f"Date: {created}"),
            ("t", f"palpbayes version: {__version__} (results written by "
                  f"{s.get('palpbayes_version', '?')})"),
            ("t", f"Results folder: {_shown(res.path)}"),
            ("t", "Campaign source: " + (_shown(s["source"]) if s.get("source")
                                         else "(traces given in code)")),
            ("t", f"{n_tr} traces, {len(groups)} material × tip groups; ground truth: "
                  f"{'yes' if _has_gt(res) else 'none'}"),
            ("", ""),
            ("h", "Settings"),
            *[("t", ln) for _, txt in _settings_lines(res) for ln in _wrap(txt, 92)],
        ]
        _text_lines(fig, info, top=0.56, left=0.06, size=10)
        size = 8.5
        fits = int((0.56 - 0.06) * PAGE_SIZE[1] * 72 / (size * 1.45)) - 2
        toc = [("h", "Contents")] + _toc_lines(contents, fits)
        _text_lines(fig, toc, top=0.56, left=0.66, size=size)
    return _Page("", build)


def _toc_lines(contents: Sequence[str], max_lines: int) -> list[tuple[str, str]]:
    """Contents lines: page number and title (wrapped, never cut), the title page left out.

    When they do not fit in ``max_lines``, each run of material × tip pages is given as one
    line ('7–33  27 material × tip pages: A · flat … B · cone'); if that is still too long, the
    list is cut with a line giving the number of pages.
    """
    def entries(collapse: bool) -> list[tuple[str, str]]:
        items: list[tuple[str, str]] = []
        i = 1
        while i < len(contents):
            t = contents[i]
            j = i
            if collapse and " · " in t and ":" not in t:
                while j + 1 < len(contents) and " · " in contents[j + 1] \
                        and ":" not in contents[j + 1]:
                    j += 1
            if j > i:
                items.append((f"{i + 1}–{j + 1}", f"{j - i + 1} material × tip pages: {t} … "
                                                  f"{contents[j]}"))
            else:
                items.append((str(i + 1), t))
            i = j + 1
        out: list[tuple[str, str]] = []
        for num, t in items:
            for k, ln in enumerate(textwrap.wrap(t, 50, break_on_hyphens=False) or [""]):
                out.append(("t", f"{num:>5}   {ln}" if k == 0 else f"{'':>5}   {ln}"))
        return out

    lines = entries(False)
    if len(lines) > max_lines:
        lines = entries(True)
    if len(lines) > max_lines:
        lines = [*lines[:max_lines - 1], ("t", f"{'':>5}   … {len(contents)} pages in all")]
    return lines


def _shown(path: str | os.PathLike | None) -> str:
    """A path as shown in the report: relative to the working folder when it is inside it or
    beside it (at most one '..'), else absolute."""
    if not path:
        return "(none)"
    p = Path(path).resolve()
    try:
        rel = Path(os.path.relpath(p, Path.cwd().resolve()))
    except ValueError:  # another drive (Windows)
        return str(p)
    if rel.parts[:2] == ("..", ".."):
        return str(p)
    return str(rel)


def _has_gt(res: ResultsFolder) -> bool:
    c = res.comparison
    return bool(c is not None and "gt_E_pa" in c and c["gt_E_pa"].notna().any())


def _coverage_line(res: ResultsFolder) -> str:
    cov = coverage_counts(res)
    if not cov:
        return ""
    parts = [f"{'Bayes' if m == 'bayes' else 'LS'}: {k}/{n}" for m, (k, n) in cov.items()]
    return ("New-specimen 90 % interval covers the ground truth in " + ", ".join(parts)
            + " material × tip groups.")


def _paper_gt_text(materials: Sequence[str]) -> str:
    """The paper's own Instron ground truth of the given materials, e.g. 'White 111 kPa'."""
    from .paper import PAPER_MATERIALS

    known = [f"{m} {PAPER_MATERIALS[m].E_pa * _KPA:g} kPa" for m in materials
             if m in PAPER_MATERIALS]
    return ", ".join(known)


def _pages_summary(res: ResultsFolder) -> list[_Page]:
    table = summary_table(res)
    title = "Summary: ground truth vs least squares vs Bayes"

    def hl(_r: int, col: str, txt: str) -> str | None:
        if "covers" in col:
            return "#fde0dc" if txt == "NO" else ("#e3f4e1" if txt == "yes" else None)
        return None

    if res.comparison is not None:
        paper_gt = _paper_gt_text(list(dict.fromkeys(table["Material"])))
        note = (
            "GT: compression ground truth, mean ± sd over the specimens of a material. LS: the "
            "paper's least squares, mean ± sd over the traces. Bayes material E: hierarchical "
            "pooling of the per-trace posteriors with the uncertainty budget applied once per "
            "group, median ± sd of the material's modulus. 'new specimen 90 %': interval for a "
            "new specimen (LS: t prediction interval; Bayes: posterior predictive), the "
            "quantity comparable with the spread of the ground truth; 'covers GT': GT inside "
            "that interval. err = (GT − E)/GT with the GT column. Paper: the published robot "
            "estimates; 'Paper err' is relative to the PAPER's own Instron ground truth"
            + (f" ({paper_gt})" if paper_gt else "") + ", not to the GT column, recomputed "
            "from the printed E. (!) marks a group with a non-converged or flagged fit.")
        if HERTZ_COL in table.columns:
            note += (" Hertz LS: the paper's choice for a sphere — least squares with the "
                     "paraboloid (Hertz) law at the sphere's radius on the same traces, mean "
                     "over the traces, and its difference from the LS column (exact Sneddon "
                     "law).")
    else:
        note = ("No comparison.csv in this folder (run 'palpbayes compare'): per-group means "
                "± sd of the per-trace estimates.")
    cover = _coverage_line(res)
    chunks = _chunks(len(table))
    per = max(c.stop - c.start for c in chunks)
    h = min(0.065, 1.0 / (per + 2.5))
    pages = []
    for k, sl in enumerate(chunks):
        part = table.iloc[sl]

        def build(fig: Figure, part: pd.DataFrame = part) -> None:
            top = 0.9
            if cover:
                fig.text(0.03, 0.905, cover, fontsize=10, fontweight="bold", va="bottom")
            ax = fig.add_axes((0.03, 0.2, 0.94, top - 0.2))
            _draw_table(ax, part, fontsize=7.5 if part.shape[1] > 10 else 9.0, highlight=hl,
                        row_height=h, wrap_header=12)
            _text_lines(fig, [("t", ln) for ln in _wrap(note, 185)], top=0.175, left=0.03,
                        size=8)
        pages.append(_Page(_continued(title, k, len(chunks)), build, rows=len(part)))
    return pages


def _material_pages(groups: Sequence[tuple[str, str]], per_page: int
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


def _pages_comparison(res: ResultsFolder) -> list[_Page]:
    comp = res.comparison
    groups = _comparison_groups(comp)
    split = _material_pages(groups, CHART_GROUPS_PER_PAGE)
    cap = ("Thick bars: each method's 90 % interval of the material's modulus (least "
           "squares: t interval of the mean over traces; Bayes: pooled posterior with the "
           "budget). Thin bars: 90 % interval for a new specimen (least squares: t "
           "prediction interval; Bayes: posterior predictive). Grey bands: ground truth "
           "mean ± sd. Open diamonds: the paper's robot estimate ± sd (relative to the paper's "
           "own ground truth).")
    if any(t == "sphere" for _, t in groups) and "E_hertz_pa" in res.summary:
        cap += (" Sphere: least squares and Bayes use the exact Sneddon law; the paper's Hertz "
                "fit of the same traces is in the summary table.")
    pages = []
    for k, part in enumerate(split):
        keys = set(part)
        sub = comp[[(str(m), str(t)) in keys
                    for m, t in zip(comp["material"], comp["tip"], strict=True)]]

        def build(fig: Figure, sub: pd.DataFrame = sub) -> None:
            ax = fig.add_axes((0.07, 0.17, 0.9, 0.69))
            plots.plot_comparison(sub, ax=ax)
            _text_lines(fig, [("t", ln) for ln in _wrap(cap, 175)], top=0.11, left=0.07,
                        size=8)
        pages.append(_Page(_continued("Comparison per material and tip", k, len(split)),
                           build, rows=len(part)))
    return pages


def _representative(res: ResultsFolder, mat: str, tip: str) -> str | None:
    """The trace shown for a group: the pooling's representative (posterior median of log E
    closest to the group median) if recorded, else the Bayes estimate closest to the median."""
    pooled = _pooled_of(res, mat, tip)
    if pooled is not None and isinstance(pooled.get("representative_trace"), str):
        tid = pooled["representative_trace"]
        if posterior_path(res.path, tid).is_file():
            return tid
    b = res.bayes_rows()
    b = b[(b["material"].fillna("").astype(str) == mat) & (b["tip"].astype(str) == tip)]
    b = b[b["E_pa"].notna()]
    if b.empty:
        return None
    ok = b[b["converged"].astype(str).str.lower() == "true"]
    pick = ok if len(ok) else b
    med = float(np.median(pick["E_pa"]))
    i = int(np.argmin(np.abs(pick["E_pa"].to_numpy(dtype=float) - med)))
    tid = str(pick["trace_id"].iloc[i])
    return tid if posterior_path(res.path, tid).is_file() else None


def _gt_of(res: ResultsFolder, mat: str) -> tuple[float, float] | None:
    c = res.comparison
    if c is not None and "gt_E_pa" in c:
        sub = c[c["material"].astype(str) == mat]["gt_E_pa"].dropna()
        if len(sub):
            sd = c[c["material"].astype(str) == mat]["gt_sd_pa"].dropna()
            return float(sub.iloc[0]), float(sd.iloc[0]) if len(sd) else float("nan")
    g = res.groundtruth_summary
    if g is not None and mat in set(g["material"].astype(str)):
        r = g[g["material"].astype(str) == mat].iloc[0]
        return float(r["E_mean_pa"]), float(r["E_sd_pa"])
    return None


def _pooled_of(res: ResultsFolder, mat: str, tip: str) -> pd.Series | None:
    p = res.pooled
    if p is None:
        return None
    sub = p[(p["material"].astype(str) == mat) & (p["tip"].astype(str) == tip)]
    return None if sub.empty else sub.iloc[0]


def _page_group(res: ResultsFolder, mat: str, tip: str, seed: int) -> _Page:
    def build(fig: Figure) -> None:
        tid = _representative(res, mat, tip)
        s = res.summary
        sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
        gt = _gt_of(res, mat)
        pooled = _pooled_of(res, mat, tip)
        gs = fig.add_gridspec(2, 3, left=0.06, right=0.98, top=0.84, bottom=0.1, wspace=0.32,
                              hspace=0.42)
        ax_fd = fig.add_subplot(gs[0, 0:2])
        ax_forest = fig.add_subplot(gs[0, 2])
        # room for the forest plot's trace-id tick labels (they would run into the force panel)
        x0, y0, w, h = ax_forest.get_position().bounds
        ax_forest.set_position([x0 + 0.045, y0, w - 0.045, h])
        ax_res = fig.add_subplot(gs[1, 0])
        ax_e = fig.add_subplot(gs[1, 1])
        ax_pair = fig.add_subplot(gs[1, 2])
        plots.plot_forest(sub[sub["E_pa"].notna()], pooled, gt=gt, ax=ax_forest,
                          title="Per trace and pooled (90 % intervals)")
        if tid is None:
            for a in (ax_fd, ax_res, ax_e, ax_pair):
                a.set_axis_off()
            ax_fd.text(0.5, 0.5, "no Bayesian posterior for this group", ha="center")
        else:
            fit = load_fit(res, tid)
            plots.plot_force_depth(fit, ax=ax_fd, seed=seed)
            ax_fd.set_title(f"Representative trace {tid} ({fit.data.model.describe()})",
                            fontsize="medium")
            plots.plot_residuals(fit, ax=ax_res)
            plots.plot_posterior_E(fit, ax=ax_e)
            plots.plot_pair(fit, ax=ax_pair, seed=seed)
        txt = []
        if pooled is not None:
            txt.append(f"Pooled ({int(pooled['n_traces'])} traces): E = "
                       f"{_fmt(pooled['E_pa'] * _KPA)} kPa, 90 % "
                       f"{_interval(pooled['E_lo_pa'], pooled['E_hi_pa'], 1)}; new specimen "
                       f"{_interval(pooled['E_new_lo_pa'], pooled['E_new_hi_pa'], 1)} kPa; "
                       f"between-trace sd of log E tau = {_fmt(pooled.get('tau'), 3)}")
        if gt is not None:
            txt.append(f"Ground truth: {_fmt(gt[0] * _KPA)} ± {_fmt(gt[1] * _KPA)} kPa")
        fig.text(0.06, 0.905, "    ".join(txt), fontsize=8.5, color="0.2")
        hz = _hertz_line(res, mat, tip)
        if hz:
            fig.text(0.06, 0.882, hz, fontsize=8.5, color="#8a3b00")
    return _Page(f"{mat} · {tip}" if mat else tip, build)


def _hertz_line(res: ResultsFolder, mat: str, tip: str) -> str:
    """Sphere pages: the paper's Hertz fit of the same traces against the exact Sneddon law."""
    h = _hertz_of_group(res, mat, tip)
    if h is None:
        return ""
    s = res.summary
    ls = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)
           & (s["method"] == "lsq")]
    e = pd.to_numeric(ls["E_pa"], errors="coerce").dropna()
    sd = f" ± {_fmt(h[1] * _KPA)}" if math.isfinite(h[1]) else ""
    ref = (f"least squares with the exact Sneddon law ({_fmt(e.mean() * _KPA)} kPa)"
           if len(e) else "the exact Sneddon law")
    return (f"Paper's Hertz fit of the same {h[3]} trace(s) (least squares, paraboloid law at "
            f"the sphere's radius): E = {_fmt(h[0] * _KPA)}{sd} kPa, Δ = {100 * h[2]:+.1f} % "
            f"vs {ref}.")


def _truthy(v: Any) -> bool:
    if isinstance(v, str):
        return v.strip().lower() == "true"
    return bool(v) if v is not None and not (isinstance(v, float) and math.isnan(v)) else False


def _range(lo: Any, hi: Any, digits: int = 0) -> str:
    """'lo–hi', or a single number when both are equal ('1500', not '1500–1500')."""
    a, b = _fmt(lo, digits), _fmt(hi, digits)
    return a if a == b else f"{a}–{b}"


def _flagged(res: ResultsFolder) -> pd.DataFrame:
    b = res.bayes_rows().copy()
    flags = b["flags"].astype(str) if "flags" in b else pd.Series("", index=b.index)
    bad = ~b["converged"].map(_truthy) | (flags.str.len() > 0)
    return b[bad]


def _diag_highlight(gtab: pd.DataFrame) -> Callable[[int, str, str], str | None]:
    """Red cells: a group with fewer converged fits than fits, or a non-converged pool."""
    def hl(r: int, col: str, txt: str) -> str | None:
        if col == "pooled conv." and txt == "NO":
            return "#fde0dc"
        if col == "converged" and txt != gtab["fits"].iloc[r]:
            return "#fde0dc"
        return None
    return hl


def _page_diagnostics(res: ResultsFolder) -> list[_Page]:
    from .bayes.diagnostics import ESS_MIN, RHAT_MAX

    b = res.bayes_rows()
    flagged = _flagged(res)
    rmax = float(b["rhat_max"].max()) if len(b) else float("nan")
    emin = float(b["ess_min"].min()) if len(b) else float("nan")
    crit = (f"criteria: R-hat ≤ {RHAT_MAX}, bulk and tail ESS ≥ {ESS_MIN:.0f}, autocorrelation "
            "time stable before the step cap, no prior-dominated surface or bound-hitting E*")
    pooled_bad: list[str] = []
    if res.pooled is not None and "converged" in res.pooled:
        pooled_bad = [f"{r['material']} {r['tip']}" for _, r in res.pooled.iterrows()
                      if not _truthy(r["converged"])]
    if len(b) == 0:
        head = "No Bayesian fits in this folder."
    elif flagged.empty:
        head = (f"All {len(b)} Bayesian fits converged: largest R-hat {rmax:.4f}, smallest ESS "
                f"{emin:.0f}.")
    else:
        head = (f"{len(flagged)} of {len(b)} Bayesian fits are NOT converged or are flagged "
                f"(largest R-hat {rmax:.4f}, smallest ESS {emin:.0f}); their numbers are "
                "marked in every table.")
    if pooled_bad:
        head += (f" Pooled (hierarchical) chain not converged for: {', '.join(pooled_bad)} "
                 "(marked (!) in the summary table).")
    elif res.pooled is not None and len(res.pooled):
        head += f" All {len(res.pooled)} pooled (hierarchical) chains converged."
    groups = []
    for mat, tip in res.groups():
        g = b[(b["material"].fillna("").astype(str) == mat) & (b["tip"].astype(str) == tip)]
        if g.empty:
            continue
        pooled = _pooled_of(res, mat, tip)
        groups.append({
            "Material": mat, "Tip": tip, "fits": str(len(g)),
            "converged": str(int(g["converged"].map(_truthy).sum())),
            "max R-hat": _fmt(g["rhat_max"].max(), 4), "min ESS": _fmt(g["ess_min"].min(), 0),
            "max tau [steps]": _fmt(g["tau_max"].max(), 1),
            "steps": _range(g["n_steps"].min(), g["n_steps"].max()),
            "acceptance": _fmt(g["acceptance"].mean(), 2),
            "pooled R-hat": "–" if pooled is None else _fmt(pooled.get("rhat_max"), 4),
            "pooled ESS": "–" if pooled is None else _fmt(pooled.get("ess_min"), 0),
            "pooled conv.": "–" if pooled is None else _yesno(pooled.get("converged")),
        })
    gtab = pd.DataFrame(groups)
    ftab = pd.DataFrame([{
        "Trace": r["trace_id"], "converged": _yesno(r["converged"]),
        "R-hat": _fmt(r["rhat_max"], 4), "ESS": _fmt(r["ess_min"], 0),
        "steps": _fmt(r["n_steps"], 0),
        "flags": textwrap.shorten(str(r["flags"]) if pd.notna(r["flags"]) else "", 95),
    } for _, r in flagged.iterrows()])
    # pages: the group table in chunks, then the flagged fits in chunks; the first flagged
    # chunk shares the last group page when both fit in TABLE_ROWS_PER_PAGE rows
    layout: list[tuple[pd.DataFrame | None, pd.DataFrame | None]] = \
        [(gtab.iloc[sl], None) for sl in _chunks(len(gtab))] if len(gtab) else [(None, None)]
    fchunks = [ftab.iloc[sl] for sl in _chunks(len(ftab))] if len(ftab) else []
    if fchunks:
        last_g = layout[-1][0]
        if last_g is None or len(last_g) + len(fchunks[0]) <= TABLE_ROWS_PER_PAGE:
            layout[-1] = (last_g, fchunks.pop(0))
        layout += [(None, f) for f in fchunks]
    row_h = 0.042
    pages = []
    for k, (gpart, fpart) in enumerate(layout):
        def build(fig: Figure, gpart=gpart, fpart=fpart, first=(k == 0)) -> None:
            lines = [("t", ln) for ln in _wrap(head, 150)]
            lines += [("t", crit)] if first else []
            _text_lines(fig, lines, top=0.9, left=0.04, size=10)
            top = 0.8
            if gpart is not None and len(gpart):
                hgt = row_h * (len(gpart) + 1)
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                _draw_table(ax, gpart, fontsize=8, row_height=1.0 / (len(gpart) + 1),
                            highlight=_diag_highlight(gpart))
                top -= hgt + 0.05
            if fpart is not None and len(fpart):
                fig.text(0.04, top, "Non-converged or flagged fits", fontsize=11,
                         fontweight="bold")
                top -= 0.02
                hgt = min(top - 0.06, row_h * (len(fpart) + 1))
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                _draw_table(ax, fpart, fontsize=7.5, row_height=1.0 / (len(fpart) + 1),
                            highlight=lambda _r, c, t: "#fde0dc" if c == "converged" and
                            t == "NO" else None)
        rows = max(0 if gpart is None else len(gpart), 0 if fpart is None else len(fpart))
        pages.append(_Page(_continued("Convergence diagnostics", k, len(layout)), build,
                           rows=rows))
    worst = None
    if len(b) and b["rhat_max"].notna().any():
        cand = b[b["trace_id"].map(lambda t: posterior_path(res.path, t).is_file())]
        if len(cand):
            worst = str(cand.loc[cand["rhat_max"].astype(float).idxmax(), "trace_id"])
    if worst is not None:
        def build_w(fig: Figure, tid: str = worst) -> None:
            fit = load_fit(res, tid)
            sub = fig.add_subfigure(fig.add_gridspec(1, 1, left=0.05, right=0.97, top=0.92,
                                                     bottom=0.05)[0, 0])
            plots.plot_walkers(fit, fig=sub, title=False)
        pages.append(_Page(f"Walkers of the least converged fit ({worst})", build_w))
    return pages


def _pages_budget(res: ResultsFolder) -> list[_Page]:
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
    chunks = _chunks(len(tab), BUDGET_GROUPS_PER_PAGE)  # table and chart share the page
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
            _draw_table(ax, part, fontsize=7.5, row_height=1.0 / (len(part) + 1))
            ax2 = fig.add_axes((0.64, 0.88 - row_h * (len(dtab) + 1), 0.34,
                                row_h * (len(dtab) + 1)))
            _draw_table(ax2, dtab, fontsize=7.5, row_height=1.0 / (len(dtab) + 1),
                        col_weights=[1.0, 1.6])
            fig.text(0.03, 0.885 - hgt - 0.035, "Cells: share of the variance of ln E "
                     "(relative sd of E from that input, %). Systematic inputs are shared by "
                     "the traces of a group and applied once to the pooled estimate.",
                     fontsize=8, color="0.25")
            ax3 = fig.add_axes((0.15, 0.1, 0.62, 0.88 - hgt - 0.22))
            plots.plot_budget(bpart, ax=ax3)
        pages.append(_Page(_continued("Uncertainty budget", k, len(chunks)), build,
                           rows=len(part)))
    return pages


def _stiffening_groups(res: ResultsFolder) -> list[tuple[str, str]]:
    """Groups whose Bayesian fits span enough distinct positive rest times for the law."""
    b = res.bayes_rows()
    if "rest_time_s" not in b:
        return []
    out = []
    for mat, tip in res.groups():
        g = b[(b["material"].astype(str) == mat) & (b["tip"].astype(str) == tip)]
        t = pd.to_numeric(g["rest_time_s"], errors="coerce")
        t = t[np.isfinite(t) & (t > 0) & g["E_stat_pa"].notna()]
        if t.nunique() >= STIFFENING_MIN_REST_TIMES:
            out.append((mat, tip))
    return out


def _page_stiffening(res: ResultsFolder, mat: str, tip: str, seed: int) -> _Page:
    def build(fig: Figure) -> None:
        from .stiffening import fit_stiffening_summary

        b = res.bayes_rows()
        g = b[(b["material"].astype(str) == mat) & (b["tip"].astype(str) == tip)]
        fit = fit_stiffening_summary(g, method="bayes", seed=seed)
        t = pd.to_numeric(g["rest_time_s"], errors="coerce")
        rows = g[np.isfinite(t)]
        fresh = g[~np.isfinite(t)]
        rested = None
        if len(fresh):
            r = fresh.iloc[0]
            rested = (r["E_stat_pa"], r["E_stat_lo_pa"], r["E_stat_hi_pa"])
        ax = fig.add_axes((0.07, 0.12, 0.5, 0.74))
        plots.plot_stiffening(rows["rest_time_s"].astype(float), rows["E_stat_pa"],
                              E_lo=rows["E_stat_lo_pa"], E_hi=rows["E_stat_hi_pa"], fit=fit,
                              rested=rested, ax=ax)
        tab = fit.table_of().copy()
        show = pd.DataFrame({"parameter": tab["parameter"], "unit": tab["unit"],
                             "median": tab["median"].map(lambda v: f"{v:.4g}"),
                             "90 % interval": [f"[{a:.4g}, {b:.4g}]"
                                               for a, b in zip(tab["lo"], tab["hi"],
                                                               strict=True)]})
        ax2 = fig.add_axes((0.62, 0.62, 0.35, 0.24))
        _draw_table(ax2, show, fontsize=8, row_height=1.0 / (len(show) + 1))
        lines = [("t", f"Preferred law: {fit.law}"), ("", "")]
        lines += [("t", ln) for ln in _wrap(fit.message, 62)]
        lines += [("", ""), ("t", "Statistical E of each palpation (the budget's systematic "),
                  ("t", "inputs scale the whole curve, not its shape).")]
        _text_lines(fig, lines, top=0.56, left=0.62, size=8.5)
    title = f"Stiffening after repeated palpation: {mat} · {tip}" if mat else \
        f"Stiffening after repeated palpation: {tip}"
    return _Page(title, build)


def _pages_stiffening_table(res: ResultsFolder) -> list[_Page]:
    st = res.stiffening
    if st is None or st.empty:
        return []
    cols = [c for c in st.columns if not c.startswith("_")]
    show = st[cols].copy()
    for c in show.columns:
        if pd.api.types.is_float_dtype(show[c]):
            show[c] = show[c].map(lambda v: f"{v:.4g}")
    chunks = _chunks(len(show))
    per = max(c.stop - c.start for c in chunks)
    pages = []
    for k, sl in enumerate(chunks):
        part = show.iloc[sl]

        def build(fig: Figure, part: pd.DataFrame = part) -> None:
            ax = fig.add_axes((0.03, 0.2, 0.94, 0.68))
            _draw_table(ax, part, fontsize=7, row_height=min(0.06, 1.0 / (per + 1)))
        pages.append(_Page(_continued("Stiffening (stiffening.csv)", k, len(chunks)), build,
                           rows=len(part)))
    return pages


#: What each ``SamplerSettings.moves`` value means (emcee moves).
MOVES_TEXT = MOVES  # description of each move schedule, defined beside the sampler


def _sampler_settings(recorded: dict | None) -> tuple[dict, bool]:
    """Sampler settings as a dict: the recorded ones (``settings.json``) completed by the
    package defaults; the flag says whether anything came from the defaults."""
    from dataclasses import asdict

    from .bayes.sampler import SamplerSettings

    default = asdict(SamplerSettings())
    rec = dict(recorded or {})
    missing = any(k not in rec for k in ("n_walkers", "max_steps", "min_steps", "check_every",
                                         "tau_factor", "tau_rtol", "moves"))
    return {**default, **{k: v for k, v in rec.items() if v is not None}}, missing


def _stopping_rule(smp: dict) -> str:
    """The sampler's stopping rule in words, with the numbers of ``smp``."""
    from .bayes.diagnostics import ESS_MIN, RHAT_MAX

    moves = str(smp.get("moves"))
    return (
        f"emcee, {int(smp['n_walkers'])} walkers, moves: {MOVES_TEXT.get(moves, repr(moves))}. "
        f"Stopping rule: every {int(smp['check_every'])} steps after {int(smp['min_steps'])}, "
        f"stop when the chain is longer than {float(smp['tau_factor']):g} × the integrated "
        "autocorrelation time (tau) of every parameter, tau changed by less than "
        f"{100 * float(smp['tau_rtol']):g} % since the last check, and the post-burn-in "
        f"chain passes max R-hat ≤ {RHAT_MAX:g} over every parameter and the log posterior, "
        f"and bulk and tail ESS ≥ {ESS_MIN:.0f} for every parameter — or at "
        f"{int(smp['max_steps'])} steps (then flagged). Burn-in 2·max tau, thinning "
        "floor(min tau / 2)."
    )


def _sphere_vs_hertz(d_over_r: float = 0.3) -> float:
    """Relative force of the exact Sneddon sphere vs Hertz at depth d/R (negative: less)."""
    from .contact import Tip, shape

    sph = float(shape(np.array([d_over_r]), Tip("sphere", radius=1.0))[0])
    par = float(shape(np.array([d_over_r]), Tip("paraboloid", radius=1.0))[0])
    return sph / par - 1.0


def _pooling_text(res: ResultsFolder) -> str:
    """Pooling paragraph: sampler from :data:`palpbayes.pooling.POOLING_SETTINGS`, the tau
    prior scale from ``pooled.csv`` (else :data:`palpbayes.pooling.TAU_PRIOR_SD`)."""
    from dataclasses import asdict

    from .pooling import POOLING_SETTINGS, TAU_PRIOR_SD

    scales: list[float] = []
    if res.pooled is not None and "tau_prior_sd" in res.pooled:
        scales = sorted(set(pd.to_numeric(res.pooled["tau_prior_sd"], errors="coerce")
                            .dropna().astype(float)))
    prior = ", ".join(f"{v:g}" for v in scales) if scales else f"{TAU_PRIOR_SD:g}"
    smp = asdict(POOLING_SETTINGS)
    return (
        "Per material × tip: log E_i ~ Normal(mu, tau²), fitted in two stages (Lunn et al. "
        "2013): each trace's statistical posterior of log E summarised as Normal(m_i, s_i²), "
        f"then (mu, log tau) sampled with {_stopping_rule(smp)} Flat prior on mu, "
        f"tau ~ HalfNormal({prior}) on the log-E scale. The systematic budget inputs are "
        "shared by the traces of a group and applied once to the pooled draws. 'New "
        "specimen' is the posterior predictive exp(mu + tau·z)·f, the quantity to compare "
        "with the Instron mean ± sd.")


def _methods_lines(res: ResultsFolder) -> list[tuple[str, str]]:
    from .bayes import priors as _priors
    from .contact import Tip
    from .fitdata import default_fit_fraction
    from .lsq import GRID_POINTS

    o = res.options
    W = 150
    smp, from_defaults = _sampler_settings(o.get("settings"))
    frac = o.get("fit_fraction")
    if frac is None:
        flat = default_fit_fraction(Tip("flat", radius=1.0))
        window = (f"Fit window: the paper's default, the first {100 * flat:g} % of a flat "
                  "punch's penetration is not fitted (non-linear start of contact), every "
                  "sample in contact for the other tips.")
    else:
        window = (f"Fit window: the first {100 * float(frac):g} % of the penetration is not "
                  "fitted, for every tip (fit_fraction option of this run).")
    if o.get("max_depth") is not None:
        window += f" Only samples shallower than {1e3 * float(o['max_depth']):g} mm are fitted."
    lines: list[tuple[str, str]] = [("h", "Contact models (DESIGN §1)")]
    lines += [("t", ln) for ln in _wrap(
        "Rigid axisymmetric tip on an elastic half-space, F = E*·s(d) with E* = E/(1 − nu²) and "
        "depth d = z_surf − z_tip (F = 0 for d ≤ 0). Flat punch of radius a: F = 2·a·E*·d. "
        "Paraboloid (Hertz) of radius R: F = (4/3)·E*·sqrt(R)·d^(3/2). Sphere: the exact "
        f"Sneddon solution ({abs(100 * _sphere_vs_hertz(0.3)):.1f} % "
        f"{'less' if _sphere_vs_hertz(0.3) < 0 else 'more'} force than Hertz at d/R = 0.3; "
        "the paper fitted its sphere with Hertz: its least-squares Hertz fit of every sphere "
        "trace is reported beside the Sneddon fits as E_hertz). Cone and power-law tips by the "
        "method of dimensionality reduction. Finite-thickness correction (Dimitriadis et al. "
        "2002 / Hayes et al. 1972) "
        + ("ON for this run." if o.get("thickness_correction") else
           "OFF for this run (half-space, as the paper)."), W)]
    lines += [("h", "Least-squares baseline (the paper's eqs. 12–13)")]
    lines += [("t", ln) for ln in _wrap(
        "Minimise L = Σ (F_j − k·d_j^m)² over k and z_surf subject to |F(z_surf)| ≤ F_unc "
        f"(F_unc = {_fmt(1e3 * float(o.get('f_unc', 0.048)), 0)} mN): for fixed z_surf E* has "
        f"a closed form; z_surf by a {GRID_POINTS}-point grid and bounded Brent search over the "
        "admissible range. Interval: Gauss-Newton covariance of (E*, z_surf) from the "
        "residuals, E ± t(0.95, n − 2)·sd — the textbook interval, assuming iid residuals and "
        f"ignoring the constraint. {window}", W)]
    lines += [("h", "Bayesian model per trace")]
    lines += [("t", ln) for ln in _wrap(
        f"F_j = E*·s(z_surf − z_j) + F0 + e_j, noise model '{o.get('noise', 'gaussian')}' "
        "(gaussian: iid Normal(0, sigma); ar1: stationary AR(1) with marginal sd sigma; "
        f"student: Student-t). Sampled with {_stopping_rule(smp)}"
        + (" (Sampler settings not recorded in settings.json: package defaults shown.)"
           if from_defaults else "")
        + " Convergence is checked with arviz (rank-normalised split R-hat, bulk and tail "
        "ESS, walkers as chains); a fit that fails is flagged in every table. Priors "
        "(palpbayes.bayes.priors):", W)]
    lines += [("m", ln) for ln in _priors_table(_priors.__doc__ or "")]
    lines += [("h", "Uncertainty budget (GUM Supplement 1)")]
    lines += [("t", ln) for ln in _wrap(
        "Inputs a trace cannot identify are propagated by Monte Carlo, one input draw per "
        "posterior draw: E = E*·(1 − nu²)·f_R/g_F·f_C with the Poisson ratio nu, the tip-radius "
        "tolerance f_R, the force-sensor gain g_F and a series compliance f_C (distributions on "
        "the budget page). Shares are each input's part of the variance of ln E.", W)]
    lines += [("h", "Pooling of repeated indentations")]
    lines += [("t", ln) for ln in _wrap(_pooling_text(res), W)]
    gt = res.groundtruth_summary
    if gt is not None and "window_lo" in gt:
        win = (f"{100 * float(gt['window_lo'].iloc[0]):g}–"
               f"{100 * float(gt['window_hi'].iloc[0]):g} %")
    else:
        from .groundtruth import DEFAULT_STRAIN_WINDOW

        win = (f"{100 * DEFAULT_STRAIN_WINDOW[0]:g}–{100 * DEFAULT_STRAIN_WINDOW[1]:g} % "
               "(default)")
    lines += [("h", "Ground truth")]
    lines += [("t", ln) for ln in _wrap(
        "Uniaxial compression (Instron exports): engineering stress vs strain, straight line "
        f"sigma = E·(eps − eps0) fitted over the toe-compensated strain window {win}; the "
        "material's ground truth is the mean ± sd (ddof 1) over its specimens.", W)]
    return lines


def _priors_table(doc: str) -> list[str]:
    """The parameter table of the priors docstring as plain monospaced lines."""
    import re

    out = []
    for ln in doc.strip().splitlines():
        if not ln.strip() or set(ln.strip()) <= {"=", " "}:
            continue
        if ln.startswith(("Priors of", "Parameters, in")):
            continue
        ln = re.sub(r":\w+:`([^`]+)`", r"\1", ln).replace("``", "")
        out.append(ln.rstrip())
    return out


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


# ----------------------------------------------------------------------------- report


@dataclass
class ReportInfo:
    """What :func:`build_report` wrote.

    Attributes
    ----------
    path
        The PDF.
    titles
        Page titles in order.
    n_traces
        Traces in the results folder.
    n_flagged
        Bayesian fits not converged or flagged.
    n_pooled_flagged
        Pooled (hierarchical) groups whose chain did not converge.
    table_rows
        Per page, the most rows of a table (or material × tip groups of a chart) on it; 0 for
        pages without one.  Tables are split at :data:`TABLE_ROWS_PER_PAGE` rows.
    results_shown
        The results folder as printed on the title page and in the footer.
    """

    path: Path
    titles: list[str]
    n_traces: int
    n_flagged: int
    n_pooled_flagged: int = 0
    table_rows: list[int] = field(default_factory=list)
    results_shown: str = ""

    @property
    def n_pages(self) -> int:
        return len(self.titles)


def build_report(results: str | os.PathLike | ResultsFolder, pdf: str | os.PathLike | None = None,
                 *, seed: int = 0, created: str | None = None) -> ReportInfo:
    """Write the PDF report of a results folder (pages listed in the module docstring).

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
    """
    from matplotlib.backends.backend_pdf import PdfPages

    from .io.atomic import write_with

    res = results if isinstance(results, ResultsFolder) else load_results(results)
    out = Path(pdf) if pdf is not None else res.path / REPORT_NAME
    if out.suffix.lower() != ".pdf":
        raise InputError(f"{out}: the report is a PDF; give a file name ending in .pdf")
    created = created or _dt.date.today().isoformat()
    contents: list[str] = []
    pages: list[_Page] = [_page_title(res, created, contents), *_pages_summary(res)]
    if res.comparison is not None and not res.comparison.empty:
        pages += _pages_comparison(res)
    pages += [_page_group(res, m, t, seed) for m, t in res.groups()]
    pages += _page_diagnostics(res)
    pages += _pages_budget(res)
    pages += [_page_stiffening(res, m, t, seed) for m, t in _stiffening_groups(res)]
    pages += _pages_stiffening_table(res)
    pages += _pages_methods(res)
    footer = (f"palpbayes {__version__} · campaign {res.name} · {created} · results "
              f"{_shown(res.path)}")
    titles = [p.title or "palpbayes report" for p in pages]
    contents.extend(titles)

    def write(tmp: Path) -> None:
        meta = {"Title": f"palpbayes report: {res.name}", "Creator": f"palpbayes {__version__}",
                "Subject": "Elastic modulus from robotic palpation"}
        with PdfPages(tmp, metadata=meta) as pdfp:
            for i, page in enumerate(pages, start=1):
                fig = _new_page()
                page.build(fig)
                if page.title:
                    _decorate(fig, page.title, footer, i, len(pages))
                else:
                    fig.text(0.96, 0.02, f"page {i} / {len(pages)}", fontsize=7, color="0.4",
                             ha="right")
                pdfp.savefig(fig, dpi=RASTER_DPI)

    write_with(write, out, suffix=".pdf")
    b = res.bayes_rows()
    n_pool = 0
    if res.pooled is not None and "converged" in res.pooled:
        n_pool = int((~res.pooled["converged"].map(_truthy)).sum())
    return ReportInfo(path=out, titles=titles, n_traces=int(res.summary["trace_id"].nunique()),
                      n_flagged=int(len(_flagged(res))) if len(b) else 0,
                      n_pooled_flagged=n_pool, table_rows=[p.rows for p in pages],
                      results_shown=_shown(res.path))
