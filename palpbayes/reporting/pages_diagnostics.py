"""Convergence diagnostics pages and the walkers of the least converged fit."""

from __future__ import annotations

import textwrap
from collections.abc import Callable

import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.layout import posterior_path
from ..campaign.results import ResultsFolder, load_fit
from ..io.tabular import parse_bool
from .format import fmt, fmt_range, wrap, yesno
from .layout import TABLE_ROWS_PER_PAGE, Page, text_lines
from .tables import continued, draw_table, flagged_rows, page_chunks, pooled_of


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
            f"than the statistical interval) in {' and '.join(parts)}; each names its likely "
            "cause and its effect on E in the flags column of summary.csv, and negligible "
            "failures are info lines."
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
    return (text + f": of the {n_material} fits with a material misfit, {len(widened)} have "
            "an interval widened to the envelope of the fitted model's and its plausible "
            "alternatives' (shallow half, deep half, a layer of unknown thickness), the model "
            f"form taking a median {widened.median():.0f} % of its width (summary.csv: "
            "modelform_models).")


def diagnostics_page(res: ResultsFolder) -> list[Page]:
    from ..bayes.diagnostics import ESS_MIN, RHAT_MAX

    b = res.bayes_rows()
    flagged = flagged_rows(res)
    rmax = float(b["rhat_max"].max()) if len(b) else float("nan")
    emin = float(b["ess_min"].min()) if len(b) else float("nan")
    crit = (f"criteria: R-hat ≤ {RHAT_MAX}, bulk and tail ESS ≥ {ESS_MIN:.0f}, autocorrelation "
            "time stable before the step cap, no bimodal or prior-dominated surface, no "
            "posterior at a prior bound")
    pooled_bad: list[str] = []
    if res.pooled is not None and "converged" in res.pooled:
        pooled_bad = [f"{r['material']} {r['tip']}" for _, r in res.pooled.iterrows()
                      if not parse_bool(r["converged"])]
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
    head += " " + _model_check_line(res)
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
        "steps": fmt(r["n_steps"], 0),
        "notes": textwrap.shorten(str(r["notes"]) if pd.notna(r.get("notes")) else "", 95),
    } for _, r in flagged.iterrows()])
    # pages: the group table in chunks, then the flagged fits in chunks; the first flagged
    # chunk shares the last group page when both fit in TABLE_ROWS_PER_PAGE rows
    layout: list[tuple[pd.DataFrame | None, pd.DataFrame | None]] = \
        [(gtab.iloc[sl], None) for sl in page_chunks(len(gtab))] if len(gtab) else [(None, None)]
    fchunks = [ftab.iloc[sl] for sl in page_chunks(len(ftab))] if len(ftab) else []
    if fchunks:
        last_g = layout[-1][0]
        if last_g is None or len(last_g) + len(fchunks[0]) <= TABLE_ROWS_PER_PAGE:
            layout[-1] = (last_g, fchunks.pop(0))
        layout += [(None, f) for f in fchunks]
    row_h = 0.042
    pages = []
    for k, (gpart, fpart) in enumerate(layout):
        def build(fig: Figure, gpart=gpart, fpart=fpart, first=(k == 0)) -> None:
            lines = [("t", ln) for ln in wrap(head, 150)]
            lines += [("t", crit)] if first else []
            text_lines(fig, lines, top=0.9, left=0.04, size=10)
            top = 0.8
            if gpart is not None and len(gpart):
                hgt = row_h * (len(gpart) + 1)
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                draw_table(ax, gpart, fontsize=8, row_height=1.0 / (len(gpart) + 1),
                            highlight=_diag_highlight(gpart))
                top -= hgt + 0.05
            if fpart is not None and len(fpart):
                fig.text(0.04, top, "Non-converged or flagged fits", fontsize=11,
                         fontweight="bold")
                top -= 0.02
                hgt = min(top - 0.06, row_h * (len(fpart) + 1))
                ax = fig.add_axes((0.04, top - hgt, 0.92, hgt))
                draw_table(ax, fpart, fontsize=7.5, row_height=1.0 / (len(fpart) + 1),
                            highlight=lambda _r, c, t: "#fde0dc" if c == "converged" and
                            t == "NO" else None)
        rows = max(0 if gpart is None else len(gpart), 0 if fpart is None else len(fpart))
        pages.append(Page(continued("Convergence diagnostics", k, len(layout)), build,
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
        pages.append(Page(f"Walkers of the least converged fit ({worst})", build_w))
    return pages
