"""The PDF report of a results folder: what a researcher attaches to a lab notebook.

:func:`build_report` reads a results folder (:mod:`palpbayes.results`: ``summary.csv``,
``posterior/*.nc``, ``settings.json``, ``traces.csv`` and, when present, ``comparison.csv``,
``pooled.csv``, ``budget.csv``, ``stiffening.csv``, ``groundtruth.csv`` /
``groundtruth_summary.csv``) and writes a multi-page PDF (A4 landscape, written atomically):

1. title page: campaign, date, palpbayes version, settings;
2. summary table in the layout of the paper's Table III: ground truth, least squares and Bayes
   E ± sd per material × tip, errors, whether each interval covers the ground truth, and the
   paper's robot numbers;
3. the same comparison as a figure;
4. one page per material × tip: force-depth data of a representative trace with the
   posterior-predictive band and the least-squares curve, residuals, posterior of E and of
   (E, z_surf), per-trace intervals with the pooled result;
5. convergence diagnostics (every non-converged or flagged fit, or the statement that all
   converged with the largest R-hat and smallest ESS) and the walkers of the worst fit;
6. the uncertainty budget (table and chart);
7. the stiffening law E(t) vs rest time (:mod:`palpbayes.stiffening`) for every material × tip
   whose palpations have at least :data:`STIFFENING_MIN_REST_TIMES` distinct rest times, and
   ``stiffening.csv`` when present;
8. methods: models, priors, noise model, least squares, pooling, ground-truth window.

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from . import __version__, plots
from .errors import InputError
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
    "ReportInfo",
    "summary_table",
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
REPORT_NAME = "report.pdf"
#: Resolution [dpi] of the rasterized parts (dense scatter, walker traces); text, axes,
#: curves and bands stay vector graphics.
RASTER_DPI = 110

_KPA = 1e-3
_MONO = "DejaVu Sans Mono"
#: A material × tip group gets a stiffening page when it has this many distinct rest times.
STIFFENING_MIN_REST_TIMES = 3



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


def summary_table(results: ResultsFolder) -> pd.DataFrame:
    """The report's summary table (strings, kPa), one row per material × tip.

    From ``comparison.csv`` when present: ground truth, least squares and Bayes E ± sd, their
    relative error and whether their interval covers the ground truth, the Bayesian
    new-specimen interval and the paper's robot numbers.  Without it, per-group means of the
    per-trace estimates of ``summary.csv``.
    """
    comp = results.comparison
    rows = []
    if comp is not None and not comp.empty:
        for mat, tip in _comparison_groups(comp):
            sub = comp[(comp["material"].astype(str) == mat) & (comp["tip"].astype(str) == tip)]
            by = {str(r["method"]): r for _, r in sub.iterrows()}
            any_row = sub.iloc[0]
            lsq, bay = by.get("lsq"), by.get("bayes")
            row = {
                "Material": mat, "Tip": tip,
                "n": str(int(any_row["n_traces"])) if _isnum(any_row.get("n_traces")) else "–",
                "GT E ± sd": _pm(any_row.get("gt_E_pa"), any_row.get("gt_sd_pa")),
            }
            for label, r in (("LS", lsq), ("Bayes", bay)):
                row[f"{label} E ± sd"] = "–" if r is None else _pm(r["E_pa"], r["E_sd_pa"])
                row[f"{label} new 90 %"] = "–" if r is None else _interval(
                    r.get("E_new_lo_pa"), r.get("E_new_hi_pa"))
                row[f"{label} err %"] = "–" if r is None else _fmt(r.get("rel_err_pct"))
                row[f"{label} covers"] = "–" if r is None else _yesno(r.get("gt_in_interval"))
            row["Paper E ± sd"] = _pm(any_row.get("paper_E_pa"), any_row.get("paper_sd_pa"))
            row["Paper err %"] = _fmt(any_row.get("paper_err_pct"))
            if bay is not None and not _truthy(bay.get("converged_all")):
                row["Bayes E ± sd"] += " (!)"
            rows.append(row)
        return pd.DataFrame(rows)
    s = results.summary
    for mat, tip in results.groups():
        sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
        row = {"Material": mat, "Tip": tip, "n": str(sub["trace_id"].nunique())}
        for label, m in (("LS", "lsq"), ("Bayes", "bayes")):
            e = sub.loc[sub["method"] == m, "E_pa"].astype(float)
            row[f"{label} mean E ± sd (traces)"] = _pm(e.mean(), e.std(ddof=1)) if len(e) \
                else "–"
        rows.append(row)
    return pd.DataFrame(rows)


def _comparison_groups(comp: pd.DataFrame) -> list[tuple[str, str]]:
    mats = ordered(comp["material"].astype(str), MATERIAL_ORDER)
    tips = ordered(comp["tip"].astype(str), TIP_ORDER)
    have = set(zip(comp["material"].astype(str), comp["tip"].astype(str), strict=True))
    return [(m, t) for m in mats for t in tips if (m, t) in have]


def _draw_table(ax: Axes, df: pd.DataFrame, *, fontsize: float = 8.0,
                highlight: Callable[[int, str, str], str | None] | None = None,
                col_weights: Sequence[float] | None = None, row_height: float | None = None
                ) -> None:
    """A real table (matplotlib ``table``) filling ``ax`` from the top, header shaded.

    Column widths follow the longest string of each column (or ``col_weights``).
    ``highlight(row, column, text)`` may return a cell colour.
    """
    ax.set_axis_off()
    cols = [str(c) for c in df.columns]
    text = [[str(v) for v in row] for row in df.itertuples(index=False)]
    if col_weights is None:
        col_weights = [max([len(c)] + [len(r[j]) for r in text]) + 2
                       for j, c in enumerate(cols)]
    w = np.asarray(col_weights, dtype=float)
    w = w / w.sum()
    n = len(text) + 1
    h = row_height if row_height is not None else min(1.0 / n, 0.06)
    tab = ax.table(cellText=text or [[""] * len(cols)], colLabels=cols, colWidths=list(w),
                   cellLoc="center", colLoc="center", bbox=[0.0, 1.0 - h * n, 1.0, h * n])
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    for (r, c), cell in tab.get_celld().items():
        cell.set_edgecolor("0.75")
        cell.set_linewidth(0.5)
        if r == 0:
            cell.set_facecolor("#e8eef4")
            cell.get_text().set_fontweight("bold")
        elif r % 2 == 0:
            cell.set_facecolor("#f7f7f7")
        if r > 0 and highlight is not None and r - 1 < len(text):
            color = highlight(r - 1, cols[c], text[r - 1][c])
            if color:
                cell.set_facecolor(color)


# ----------------------------------------------------------------------------- pages


@dataclass
class _Page:
    title: str
    build: Callable[[Figure], None]


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
        out.extend(textwrap.wrap(para, width) or [""])
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
    smp = o.get("settings") or {}
    if o.get("thickness_correction"):
        thick = "on (" + ("bonded" if o.get("bonded", True) else "non-bonded") + ")"
    else:
        thick = "off (half-space, as the paper)"
    frac = o.get("fit_fraction")
    frac = "paper default (0.2 flat, 0 others)" if frac is None else f"{frac:g}"
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
        ("t", f"Sampler: emcee, {smp.get('n_walkers')} walkers, moves '{smp.get('moves')}', "
              f"{smp.get('min_steps')}–{smp.get('max_steps')} steps, stopping when the chain "
              f"is longer than {smp.get('tau_factor')}·tau and tau is stable"),
    ]


def _page_title(res: ResultsFolder, created: str, contents: list[str]) -> _Page:
    def build(fig: Figure) -> None:
        fig.text(0.5, 0.78, "palpbayes report", ha="center", fontsize=30, fontweight="bold")
        fig.text(0.5, 0.71, f"Campaign: {res.name}", ha="center", fontsize=18)
        fig.text(0.5, 0.66, "Elastic modulus from robotic palpation: least squares vs Bayes, "
                 "compared with compression ground truth", ha="center", fontsize=11,
                 color="0.3")
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
        toc = [("h", "Contents")] + [("t", f"{i:>2}   {textwrap.shorten(t, 50)}")
                                     for i, t in enumerate(contents, 1) if i > 1]
        if len(toc) > 30:
            toc = [*toc[:29], ("t", f"     … {len(contents)} pages in all")]
        _text_lines(fig, toc, top=0.56, left=0.66, size=8.5)
    return _Page("", build)


def _shown(path: str | os.PathLike | None) -> str:
    """A path as shown in the report: relative to the working folder when inside it."""
    if not path:
        return "(none)"
    p = Path(path).resolve()
    try:
        return str(p.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(p)


def _has_gt(res: ResultsFolder) -> bool:
    c = res.comparison
    return bool(c is not None and "gt_E_pa" in c and c["gt_E_pa"].notna().any())


def _page_summary(res: ResultsFolder) -> _Page:
    table = summary_table(res)

    def hl(_r: int, col: str, txt: str) -> str | None:
        if col.endswith("covers"):
            return "#fde0dc" if txt == "NO" else ("#e3f4e1" if txt == "yes" else None)
        return None

    def build(fig: Figure) -> None:
        ax = fig.add_axes((0.03, 0.16, 0.94, 0.74))
        _draw_table(ax, table, fontsize=8.0 if table.shape[1] > 10 else 9.0, highlight=hl,
                    row_height=min(0.065, 1.0 / (len(table) + 1)))
        if res.comparison is not None:
            note = (
                "E in kPa. GT: compression ground truth, mean ± sd over the specimens of a "
                "material. LS: the paper's least squares, mean ± sd over the traces. Bayes: "
                "hierarchical pooling of the per-trace posteriors with the uncertainty budget "
                "applied once per group, median ± sd of the material's modulus. 'new 90 %': "
                "interval for a new specimen (LS: t prediction interval; Bayes: posterior "
                "predictive), the quantity comparable with the spread of the ground truth; "
                "'covers': GT inside that interval. err % = (GT − E)/GT as in the paper. Paper: "
                "the published robot estimates, err recomputed from the printed E. (!) marks a "
                "group with a non-converged or flagged fit.")
        else:
            note = ("No comparison.csv in this folder (run 'palpbayes compare'): per-group means "
                    "± sd of the per-trace estimates, kPa.")
        _text_lines(fig, [("t", ln) for ln in _wrap(note, 175)], top=0.13, left=0.03,
                    size=8)
    return _Page("Summary: ground truth vs least squares vs Bayes", build)


def _page_comparison(res: ResultsFolder) -> _Page:
    def build(fig: Figure) -> None:
        ax = fig.add_axes((0.07, 0.14, 0.9, 0.72))
        plots.plot_comparison(res.comparison, ax=ax)
        cap = ("Thick bars: each method's 90 % interval of the material's modulus (least "
               "squares: t interval of the mean over traces; Bayes: pooled posterior with the "
               "budget). Thin bars: 90 % interval for a new specimen (least squares: t "
               "prediction interval; Bayes: posterior predictive). Grey bands: ground truth "
               "mean ± sd. Open diamonds: the paper's robot estimate ± sd.")
        _text_lines(fig, [("t", ln) for ln in _wrap(cap, 170)], top=0.085, left=0.07,
                    size=8)
    return _Page("Comparison per material and tip", build)


def _representative(res: ResultsFolder, mat: str, tip: str) -> str | None:
    """The trace shown for a group: the pooling's representative (posterior median of log E
    closest to the group median) if recorded, else the Bayes estimate closest to the median."""
    pooled = _pooled_of(res, mat, tip)
    if pooled is not None and isinstance(pooled.get("representative_trace"), str):
        tid = pooled["representative_trace"]
        if (res.path / "posterior" / f"{tid}.nc").is_file():
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
    return tid if (res.path / "posterior" / f"{tid}.nc").is_file() else None


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
        gs = fig.add_gridspec(2, 3, left=0.06, right=0.98, top=0.86, bottom=0.1, wspace=0.32,
                              hspace=0.42)
        ax_fd = fig.add_subplot(gs[0, 0:2])
        ax_forest = fig.add_subplot(gs[0, 2])
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
    return _Page(f"{mat} · {tip}" if mat else tip, build)


def _truthy(v: Any) -> bool:
    if isinstance(v, str):
        return v.strip().lower() == "true"
    return bool(v) if v is not None and not (isinstance(v, float) and math.isnan(v)) else False


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
            "steps": f"{_fmt(g['n_steps'].min(), 0)}–{_fmt(g['n_steps'].max(), 0)}",
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
    per_page = 18
    chunks = [ftab.iloc[i:i + per_page] for i in range(0, len(ftab), per_page)] or [None]
    pages = []
    for k, chunk in enumerate(chunks):
        def build(fig: Figure, chunk=chunk, first=(k == 0)) -> None:
            lines = [("t", ln) for ln in _wrap(head, 150)]
            lines += [("t", crit)] if first else []
            _text_lines(fig, lines, top=0.9, left=0.04, size=10)
            top = 0.8
            if first and not gtab.empty:
                hgt = min(0.45, 0.042 * (len(gtab) + 1))
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                _draw_table(ax, gtab, fontsize=8, row_height=1.0 / (len(gtab) + 1),
                            highlight=_diag_highlight(gtab))
                top -= hgt + 0.05
            if chunk is not None and len(chunk):
                fig.text(0.04, top, "Non-converged or flagged fits", fontsize=11,
                         fontweight="bold")
                top -= 0.02
                hgt = min(top - 0.06, 0.04 * (len(chunk) + 1))
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                _draw_table(ax, chunk, fontsize=7.5, row_height=1.0 / (len(chunk) + 1),
                            highlight=lambda _r, c, t: "#fde0dc" if c == "converged" and
                            t == "NO" else None)
        title = "Convergence diagnostics" + (f" (continued {k + 1})" if k else "")
        pages.append(_Page(title, build))
    worst = None
    if len(b) and b["rhat_max"].notna().any():
        cand = b[b["trace_id"].map(lambda t: (res.path / "posterior" / f"{t}.nc").is_file())]
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


def _page_budget(res: ResultsFolder) -> _Page | None:
    bud = res.budget
    if bud is None or bud.empty:
        return None
    inputs = list(dict.fromkeys(bud["input"].astype(str)))
    dist = bud.drop_duplicates("input").set_index("input")["distribution"].astype(str)
    keys = [c for c in ("material", "tip") if c in bud.columns]
    rows = []
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
    tab = pd.DataFrame(rows)
    dtab = pd.DataFrame({"Input": inputs, "Distribution": [dist.get(i, "") for i in inputs]})

    def build(fig: Figure) -> None:
        hgt = min(0.5, 0.036 * (len(tab) + 1))
        ax = fig.add_axes((0.03, 0.88 - hgt, 0.58, hgt))
        _draw_table(ax, tab, fontsize=7.5, row_height=1.0 / (len(tab) + 1))
        ax2 = fig.add_axes((0.64, 0.88 - 0.036 * (len(dtab) + 1), 0.34,
                            0.036 * (len(dtab) + 1)))
        _draw_table(ax2, dtab, fontsize=7.5, row_height=1.0 / (len(dtab) + 1),
                    col_weights=[1.0, 1.6])
        fig.text(0.03, 0.885 - hgt - 0.035, "Cells: share of the variance of ln E "
                 "(relative sd of E from that input, %). Systematic inputs are shared by the "
                 "traces of a group and applied once to the pooled estimate.", fontsize=8,
                 color="0.25")
        ax3 = fig.add_axes((0.15, 0.1, 0.62, 0.88 - hgt - 0.22))
        plots.plot_budget(bud, ax=ax3)
    return _Page("Uncertainty budget", build)


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
        tab = (fit.double if fit.preferred == "double" else fit.single).copy()
        show = pd.DataFrame({"parameter": tab["parameter"], "unit": tab["unit"],
                             "median": tab["median"].map(lambda v: f"{v:.4g}"),
                             "90 % interval": [f"[{a:.4g}, {b:.4g}]"
                                               for a, b in zip(tab["lo"], tab["hi"],
                                                               strict=True)]})
        ax2 = fig.add_axes((0.62, 0.62, 0.35, 0.24))
        _draw_table(ax2, show, fontsize=8, row_height=1.0 / (len(show) + 1))
        law = ("E(t) = c1·exp(c2·t) + c3·exp(c4·t)" if fit.preferred == "double"
               else "E(t) = c0 + c1·exp(c2·t)")
        lines = [("t", f"Preferred law: {law}"), ("", "")]
        lines += [("t", ln) for ln in _wrap(fit.message, 62)]
        lines += [("", ""), ("t", "Statistical E of each palpation (the budget's systematic "),
                  ("t", "inputs scale the whole curve, not its shape).")]
        _text_lines(fig, lines, top=0.56, left=0.62, size=8.5)
    title = f"Stiffening after repeated palpation: {mat} · {tip}" if mat else \
        f"Stiffening after repeated palpation: {tip}"
    return _Page(title, build)


def _page_stiffening_table(res: ResultsFolder) -> _Page | None:
    st = res.stiffening
    if st is None or st.empty:
        return None
    cols = [c for c in st.columns if not c.startswith("_")]

    def build(fig: Figure) -> None:
        show = st[cols].copy()
        for c in show.columns:
            if pd.api.types.is_float_dtype(show[c]):
                show[c] = show[c].map(lambda v: f"{v:.4g}")
        ax = fig.add_axes((0.03, 0.2, 0.94, 0.68))
        _draw_table(ax, show, fontsize=7, row_height=min(0.06, 1.0 / (len(show) + 1)))
    return _Page("Stiffening (stiffening.csv)", build)


def _methods_lines(res: ResultsFolder) -> list[tuple[str, str]]:
    from .bayes import priors as _priors

    o = res.options
    W = 150
    lines: list[tuple[str, str]] = [("h", "Contact models (DESIGN §1)")]
    lines += [("t", ln) for ln in _wrap(
        "Rigid axisymmetric tip on an elastic half-space, F = E*·s(d) with E* = E/(1 − nu²) and "
        "depth d = z_surf − z_tip (F = 0 for d ≤ 0). Flat punch of radius a: F = 2·a·E*·d. "
        "Paraboloid (Hertz) of radius R: F = (4/3)·E*·sqrt(R)·d^(3/2). Sphere: the exact "
        "Sneddon solution (about 3 % less force than Hertz at d/R = 0.3; the paper fitted its "
        "sphere with Hertz). Cone and power-law tips by the method of dimensionality "
        "reduction. Finite-thickness correction (Dimitriadis et al. 2002 / Hayes et al. 1972) "
        + ("ON for this run." if o.get("thickness_correction") else
           "OFF for this run (half-space, as the paper)."), W)]
    lines += [("h", "Least-squares baseline (the paper's eqs. 12–13)")]
    lines += [("t", ln) for ln in _wrap(
        "Minimise L = Σ (F_j − k·d_j^m)² over k and z_surf subject to |F(z_surf)| ≤ F_unc "
        f"(F_unc = {_fmt(1e3 * float(o.get('f_unc', 0.048)), 0)} mN): for fixed z_surf E* has "
        "a closed form; z_surf by a 64-point grid and bounded Brent search over the admissible "
        "range. Interval: Gauss-Newton covariance of (E*, z_surf) from the residuals, "
        "E ± t(0.95, n − 2)·sd — the textbook interval, assuming iid residuals and ignoring the "
        "constraint. Flat punch: the first 20 % of the penetration is not fitted (paper).", W)]
    lines += [("h", "Bayesian model per trace")]
    lines += [("t", ln) for ln in _wrap(
        f"F_j = E*·s(z_surf − z_j) + F0 + e_j, noise model '{o.get('noise', 'gaussian')}' "
        "(gaussian: iid Normal(0, sigma); ar1: stationary AR(1) with marginal sd sigma; "
        "student: Student-t). Sampled with emcee (80 % DEMove + 20 % DESnookerMove) until the "
        "chain is longer than 100 autocorrelation times and tau is stable; burn-in 2·tau "
        "discarded. Convergence: rank-normalised split R-hat ≤ 1.01 and bulk/tail ESS ≥ 400 "
        "(arviz, walkers as chains). Priors (palpbayes.bayes.priors):", W)]
    lines += [("m", ln) for ln in _priors_table(_priors.__doc__ or "")]
    lines += [("h", "Uncertainty budget (GUM Supplement 1)")]
    lines += [("t", ln) for ln in _wrap(
        "Inputs a trace cannot identify are propagated by Monte Carlo, one input draw per "
        "posterior draw: E = E*·(1 − nu²)·f_R/g_F·f_C with the Poisson ratio nu, the tip-radius "
        "tolerance f_R, the force-sensor gain g_F and a series compliance f_C (distributions on "
        "the budget page). Shares are each input's part of the variance of ln E.", W)]
    lines += [("h", "Pooling of repeated indentations")]
    lines += [("t", ln) for ln in _wrap(
        "Per material × tip: log E_i ~ Normal(mu, tau²), fitted in two stages (Lunn et al. "
        "2013): each trace's statistical posterior of log E summarised as Normal(m_i, s_i²), "
        "then (mu, log tau) sampled with emcee; flat prior on mu, tau ~ HalfNormal(0.5). The "
        "systematic budget inputs are shared by the traces of a group and applied once to the "
        "pooled draws. 'New specimen' is the posterior predictive exp(mu + tau·z)·f, the "
        "quantity to compare with the Instron mean ± sd.", W)]
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
        pages.append(_Page("Methods" + (f" (continued {k + 1})" if k else ""), build))
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
    """

    path: Path
    titles: list[str]
    n_traces: int
    n_flagged: int
    n_pooled_flagged: int = 0

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
    pages: list[_Page] = [_page_title(res, created, contents), _page_summary(res)]
    if res.comparison is not None and not res.comparison.empty:
        pages.append(_page_comparison(res))
    pages += [_page_group(res, m, t, seed) for m, t in res.groups()]
    pages += _page_diagnostics(res)
    budget = _page_budget(res)
    if budget is not None:
        pages.append(budget)
    pages += [_page_stiffening(res, m, t, seed) for m, t in _stiffening_groups(res)]
    table = _page_stiffening_table(res)
    if table is not None:
        pages.append(table)
    pages += _pages_methods(res)
    footer = f"palpbayes {__version__} · campaign {res.name} · {created} · {_shown(res.path)}"
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
                      n_pooled_flagged=n_pool)
