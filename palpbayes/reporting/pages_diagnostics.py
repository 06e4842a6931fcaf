"""Convergence diagnostics pages and the walkers of the least converged fit."""

from __future__ import annotations

from collections.abc import Callable

import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder, load_fit
from ..flagcodes import flag_level, split_flags
from ..io.tabular import parse_bool
from ..outputs import posterior_path
from .format import fmt, fmt_range, yesno
from .layout import PAGE_SIZE, Page, text_height, text_lines
from .tables import (
    continued,
    draw_table,
    flagged_rows,
    page_chunks,
    pooled_of,
    table_layout,
)


def _diag_highlight(gtab: pd.DataFrame) -> Callable[[int, str, str], str | None]:
    """Red cells: a group with fewer converged fits than fits, or a non-converged pool."""
    def hl(r: int, col: str, txt: str) -> str | None:
        if col == "pooled conv." and txt == "NO":
            return "#fde0dc"
        if col == "converged" and txt != gtab["fits"].iloc[r]:
            return "#fde0dc"
        return None
    return hl


def _model_check_line(res: ResultsFolder) -> str:
    """How many fits of each method fail a model-adequacy check, and the causes named most."""
    s = res.summary
    if "model_ok" not in s:
        return "Model checks: not run (results of an older palpbayes)."
    parts = []
    n_material = 0  # Bayesian fits with a material misfit
    for method, label in (("bayes", "Bayesian"), ("lsq", "least-squares")):
        m = s[s["method"] == method]
        ran = m[m["model_ok"].notna()]
        if len(ran):
            bad_rows = ran[~ran["model_ok"].map(parse_bool)]
            if method == "bayes":
                n_material = len(bad_rows)
            text = f"{len(bad_rows)} of {len(ran)} {label} fits"
            if len(bad_rows) and "misfit_effect" in bad_rows:
                eff = 100 * bad_rows["misfit_effect"].abs()
                if eff.notna().any():
                    text += f" (effect on E up to {eff.max():.0f} %)"
            parts.append(text)
    if not parts:
        return "Model checks: none ran."
    return ("Model checks (free exponent, residual structure, depth consistency, posterior "
            f"predictive) find a material misfit (one that moves E by more than 2 % and more "
            f"than the statistical interval) in {' and '.join(parts)}; summary.csv names the "
            "checks (misfit_checks) and the effect on E (misfit_effect), and gives each "
            "failure's likely cause in words in notes (codes in flag_codes, the level in "
            "flag_level); negligible failures are info lines there."
            + _model_form_sentence(s[s["method"] == "bayes"], n_material))


def _model_form_sentence(b: pd.DataFrame, n_material: int) -> str:
    """The interval's three parts over the Bayesian fits ``b`` (statistical, budget, model
    form), ``n_material`` of which have a material misfit."""
    if "modelform_share_pct" not in b or b.empty:
        return ""
    share = pd.to_numeric(b["modelform_share_pct"], errors="coerce")
    widened = share[share > 0]
    stat = 100 * (b["E_stat_hi_pa"] - b["E_stat_lo_pa"]) / b["E_pa"]
    bud = 100 * (b["E_budget_hi_pa"] - b["E_budget_lo_pa"]) / b["E_pa"]
    text = (f" E's 90 % interval (E_lo..E_hi) has three parts: statistical (median width "
            f"{stat.median():.2g} % of E), + budget ({bud.median():.2g} %), + model form")
    if widened.empty:
        return text + (": none (no Bayesian fit has a material misfit)." if n_material == 0
                       else f": none (the {n_material} fits with a material misfit were run "
                       "without it, or their alternatives fall inside the budget interval).")
    of = ("of the fit with a material misfit" if n_material == 1
          else f"of the {n_material} fits with a material misfit")
    return (text + f": {of}, {len(widened)} " + ("has" if len(widened) == 1 else "have")
            + " an interval widened to the envelope of the fitted model's and its plausible "
            "alternatives' (shallow half, deep half, a layer of unknown thickness), the model "
            f"form taking a median {widened.median():.0f} % of its width (summary.csv: "
            "modelform_models).")


def _fits(n: int) -> str:
    return f"{n} Bayesian fit" + ("" if n == 1 else "s")


def convergence_head(res: ResultsFolder) -> str:
    """The diagnostics page's first paragraph: fits not converged, and, separately, converged
    fits with a warning (a failed model check or a posterior flag), then the pooled chains and
    the model checks."""
    b = res.bayes_rows()
    rmax = float(b["rhat_max"].max()) if len(b) else float("nan")
    emin = float(b["ess_min"].min()) if len(b) else float("nan")
    conv = b["converged"].map(parse_bool) if len(b) else b.get("converged")
    warned = (b["flag_level"].fillna("").astype(str) == "warning") if "flag_level" in b \
        else pd.Series(False, index=b.index)
    stats = f"largest R-hat {rmax:.4f}, smallest ESS {emin:.0f}"
    if len(b) == 0:
        head = "No Bayesian fits in this folder."
    else:
        n_bad = int((~conv).sum())
        n_ok = len(b) - n_bad
        if n_bad == 0:
            head = (f"The Bayesian fit converged ({stats})." if len(b) == 1
                    else f"All {len(b)} Bayesian fits converged ({stats}).")
        else:
            head = (f"{n_bad} of {_fits(len(b))} did NOT converge ({stats}); the table "
                    "below lists them.")
        n_warn = int((conv & warned).sum())
        if n_warn:
            which = ("It carries" if n_ok == 1 else
                     f"{n_warn} of the {n_ok} converged fits carry" if n_bad else
                     f"{n_warn} of them carry")
            head += (f" {which} a warning (a failed model check or a posterior flag): listed "
                     "below with every note.")
    pooled_bad: list[str] = []
    if res.pooled is not None and "converged" in res.pooled:
        pooled_bad = [f"{r['material']} {r['tip']}" for _, r in res.pooled.iterrows()
                      if not parse_bool(r["converged"])]
    if pooled_bad:
        head += (f" Pooled (hierarchical) chain not converged for: {', '.join(pooled_bad)} "
                 "(marked (!) in the summary table).")
    elif res.pooled is not None and len(res.pooled):
        head += f" All {len(res.pooled)} pooled (hierarchical) chains converged."
    return head + " " + _model_check_line(res)


def _notes(value) -> str:
    """A fit's notes, one flag a line (warnings first, then information), in full."""
    text = str(value) if pd.notna(value) else ""
    flags = [f.strip() for f in split_flags(text) if f.strip()]  # "; " inside brackets stays
    order = sorted(flags, key=lambda f: flag_level(f) != "warning")  # stable: warnings first
    return "\n".join("• " + f for f in order)


#: Layout of the diagnostics pages [figure fraction]: the text's top, the tables' bottom,
#: the row height of a table, the gap below a text or table.
_TOP, _BOTTOM, _ROW, _GAP = 0.9, 0.06, 0.042, 0.03
_SIZE = 9.5  # [pt] the page's text


def diagnostics_page(res: ResultsFolder) -> list[Page]:
    from ..bayes.diagnostics import ESS_MIN, RHAT_MAX

    b = res.bayes_rows()
    flagged = flagged_rows(res)
    crit = (f"Criteria: R-hat ≤ {RHAT_MAX}, bulk and tail ESS ≥ {ESS_MIN:.0f}, autocorrelation "
            "time stable before the step cap, no bimodal or prior-dominated surface, no "
            "posterior at a prior bound.")
    head = convergence_head(res)
    groups = []
    for mat, tip in res.groups():
        g = b[(b["material"].fillna("").astype(str) == mat) & (b["tip"].astype(str) == tip)]
        if g.empty:
            continue
        pooled = pooled_of(res, mat, tip)
        groups.append({
            "Material": mat, "Tip": tip, "fits": str(len(g)),
            "converged": str(int(g["converged"].map(parse_bool).sum())),
            "max R-hat": fmt(g["rhat_max"].max(), 4), "min ESS": fmt(g["ess_min"].min(), 0),
            "max tau [steps]": fmt(g["tau_max"].max(), 1),
            "steps": fmt_range(g["n_steps"].min(), g["n_steps"].max()),
            "acceptance": fmt(g["acceptance"].mean(), 2),
            "pooled R-hat": "–" if pooled is None else fmt(pooled.get("rhat_max"), 4),
            "pooled ESS": "–" if pooled is None else fmt(pooled.get("ess_min"), 0),
            "pooled conv.": "–" if pooled is None else yesno(pooled.get("converged")),
        })
    gtab = pd.DataFrame(groups)
    ftab = pd.DataFrame([{
        "Trace": r["trace_id"], "converged": yesno(r["converged"]),
        "R-hat": fmt(r["rhat_max"], 4), "ESS": fmt(r["ess_min"], 0),
        "steps": fmt(r["n_steps"], 0), "notes (summary.csv)": _notes(r.get("notes")),
    } for _, r in flagged.iterrows()])
    first = [("t", head), ("t", crit)]
    later = [("t", "Convergence diagnostics continued: " + _fits(len(b)) + " in all.")]
    return _pages(gtab, ftab, first, later) + _walker_pages(res, b)


def _flag_rows_height(ftab: pd.DataFrame) -> list[float]:
    """Height of each flagged-fit row as drawn [figure fraction] (its notes wrapped, in
    full)."""
    if ftab.empty:
        return []
    w, h = PAGE_SIZE
    lay = table_layout(ftab, 0.92 * w * 72, fontsize=7.5, one_row=_ROW * h * 72,
                       min_fontsize=7.5)
    return [x / 72 / h for x in lay.heights[1:]]


def _pages(gtab: pd.DataFrame, ftab: pd.DataFrame, first: list[tuple[str, str]],
           later: list[tuple[str, str]]) -> list[Page]:
    """The group table in chunks, then the flagged fits, as many rows a page as fit below the
    text (a fit's notes are never cut: its row grows)."""
    head_h = {True: text_height(first, size=_SIZE, left=0.04),
              False: text_height(later, size=_SIZE, left=0.04)}
    items: list[tuple[str, pd.DataFrame]] = [("g", gtab.iloc[sl])
                                            for sl in page_chunks(len(gtab))] if len(gtab) \
        else []
    heights = _flag_rows_height(ftab)
    pages_spec: list[list[tuple[str, pd.DataFrame]]] = []
    cur: list[tuple[str, pd.DataFrame]] = []
    room = _TOP - head_h[True] - _GAP - _BOTTOM
    for kind, part in items:
        need = _ROW * (len(part) + 1) + _GAP
        if cur and need > room:
            pages_spec.append(cur)
            cur, room = [], _TOP - head_h[False] - _GAP - _BOTTOM
        cur.append((kind, part))
        room -= need
    i = 0
    while i < len(ftab):
        title_h = 0.045 + _ROW  # the heading and the table's header row
        j = i
        used = title_h
        while j < len(ftab) and (j == i and not cur or used + heights[j] <= room):
            used += heights[j]
            j += 1
        if j == i:  # not one row fits below what is on the page: a new page
            pages_spec.append(cur)
            cur, room = [], _TOP - head_h[False] - _GAP - _BOTTOM
            continue
        cur.append(("f", ftab.iloc[i:j]))
        room -= used + _GAP
        i = j
    if cur or not pages_spec:
        pages_spec.append(cur)

    pages = []
    for k, spec in enumerate(pages_spec):
        def build(fig: Figure, spec=spec, lines=first if k == 0 else later) -> None:
            top = text_lines(fig, lines, top=_TOP, left=0.04, size=_SIZE) - _GAP
            for kind, part in spec:
                if kind == "g":
                    hgt = _ROW * (len(part) + 1)
                    ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                    top -= draw_table(ax, part, fontsize=8, row_height=1.0 / (len(part) + 1),
                                      highlight=_diag_highlight(part)) + _GAP
                else:
                    fig.text(0.04, top, "Fits not converged or with a warning", fontsize=11,
                             fontweight="bold", va="top")
                    top -= 0.045
                    hgt = max(top - _BOTTOM, _ROW)
                    ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                    top -= draw_table(ax, part, fontsize=7.5, row_height=_ROW / hgt,
                                      left=("notes (summary.csv)",), min_fontsize=7.5,
                                      highlight=lambda _r, c, t: "#fde0dc"
                                      if c == "converged" and t == "NO" else None) + _GAP
        rows = max([len(p) for _, p in spec] or [0])
        pages.append(Page(continued("Convergence diagnostics", k, len(pages_spec)), build,
                          rows=rows))
    return pages


def _walker_pages(res: ResultsFolder, b: pd.DataFrame) -> list[Page]:
    """The walkers of the least converged fit with a stored posterior (none without one)."""
    pages: list[Page] = []
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
        pages.append(Page(f"Walkers of the least converged fit ({worst})", build_w))
    return pages
