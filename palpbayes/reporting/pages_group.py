"""One page per material × tip: a representative trace's fit and posteriors, and the
per-trace intervals with the pooled result."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder, load_fit
from ..outputs import posterior_path
from .format import fmt, interval, kpa, pm
from .layout import Page, text_lines, wrap_to
from .tables import hertz_of_group, pooled_of


def _representative(res: ResultsFolder, mat: str, tip: str) -> str | None:
    """The trace shown for a group: the pooling's representative (posterior median of log E
    closest to the group median) if recorded, else the Bayes estimate closest to the median."""
    pooled = pooled_of(res, mat, tip)
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


def group_page(res: ResultsFolder, mat: str, tip: str, seed: int) -> Page:
    def build(fig: Figure) -> None:
        tid = _representative(res, mat, tip)
        s = res.summary
        sub = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)]
        gt = _gt_of(res, mat)
        pooled = pooled_of(res, mat, tip)
        txt = []
        if pooled is not None:
            txt.append(f"Pooled ({int(pooled['n_traces'])} traces): E = "
                       f"{kpa(pooled['E_pa'])} kPa, 90 % "
                       f"{interval(pooled['E_lo_pa'], pooled['E_hi_pa'])}; new specimen "
                       f"{interval(pooled['E_new_lo_pa'], pooled['E_new_hi_pa'])} kPa; "
                       f"between-trace sd of log E tau = {fmt(pooled.get('tau'), 3)}")
        if gt is not None:
            txt.append(f"Ground truth: {pm(*gt)} kPa")
        # the group's numbers under the page title, wrapped; the panels below them
        top = 0.925
        if txt:
            top = text_lines(fig, [("t", "    ".join(txt))], top=top, left=0.06, size=8.5,
                             width=0.92)
        hz = _hertz_line(res, mat, tip)
        if hz:
            y0 = len(fig.texts)
            top = text_lines(fig, [("t", hz)], top=top, left=0.06, size=8.5, width=0.92)
            for t in fig.texts[y0:]:
                t.set_color("#8a3b00")
        fit = load_fit(res, tid) if tid is not None else None
        gs = fig.add_gridspec(2, 3, left=0.06, right=0.98, top=min(0.84, top - 0.04),
                              bottom=0.1, wspace=0.32, hspace=0.42)
        ax_fd = fig.add_subplot(gs[0, 0:2])
        title = ("" if fit is None
                 else f"Representative trace {tid} ({fit.data.model.describe()})")
        width = ax_fd.get_position().width * fig.get_figwidth() * 72
        title_lines = wrap_to(title, width, 10.0)
        if len(title_lines) > 1:  # a long model description: room for its lines
            gs.update(top=min(0.84, top - 0.04) - 0.02 * (len(title_lines) - 1))
        ax_forest = fig.add_subplot(gs[0, 2])
        # room for the forest plot's trace-id tick labels (they would run into the force panel)
        x0, y0, w, h = ax_forest.get_position().bounds
        ax_forest.set_position([x0 + 0.045, y0, w - 0.045, h])
        ax_res = fig.add_subplot(gs[1, 0])
        ax_e = fig.add_subplot(gs[1, 1])
        ax_pair = fig.add_subplot(gs[1, 2])
        plots.plot_forest(sub[sub["E_pa"].notna()], pooled, gt=gt, ax=ax_forest,
                          title="Per trace and pooled (90 % intervals)")
        if fit is None:
            for a in (ax_fd, ax_res, ax_e, ax_pair):
                a.set_axis_off()
            ax_fd.text(0.5, 0.5, "no Bayesian posterior for this group", ha="center")
        else:
            plots.plot_force_depth(fit, ax=ax_fd, seed=seed)
            ax_fd.set_title("\n".join(title_lines), fontsize=10.0)
            plots.plot_residuals(fit, ax=ax_res)
            plots.plot_posterior_E(fit, ax=ax_e)
            plots.plot_pair(fit, ax=ax_pair, seed=seed)
    return Page(f"{mat} · {tip}" if mat else tip, build)


def _hertz_line(res: ResultsFolder, mat: str, tip: str) -> str:
    """Sphere pages: the paper's Hertz fit of the same traces against the exact Sneddon law."""
    h = hertz_of_group(res, mat, tip)
    if h is None:
        return ""
    s = res.summary
    ls = s[(s["material"].fillna("").astype(str) == mat) & (s["tip"].astype(str) == tip)
           & (s["method"] == "lsq")]
    e = pd.to_numeric(ls["E_pa"], errors="coerce").dropna()
    sd = f" ± {kpa(h[1])}" if math.isfinite(h[1]) else ""
    ref = (f"least squares with the exact Sneddon law ({kpa(e.mean())} kPa)"
           if len(e) else "the exact Sneddon law")
    return (f"Paper's Hertz fit of the same {h[3]} trace(s) (least squares, paraboloid law at "
            f"the sphere's radius): E = {kpa(h[0])}{sd} kPa, Δ = {100 * h[2]:+.1f} % "
            f"vs {ref}.")
