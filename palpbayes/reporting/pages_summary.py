"""The summary table pages (the paper's Table III layout) and the comparison charts."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder
from ..contact import registered_laws
from .format import KPA, wrap
from .layout import CHART_GROUPS_PER_PAGE, Page, text_height, text_lines
from .tables import (
    HERTZ_COL,
    INSTRON_COL,
    comparison_groups,
    continued,
    coverage_counts,
    draw_table,
    material_pages,
    page_chunks,
    summary_table,
)


def _coverage_line(res: ResultsFolder) -> str:
    cov = coverage_counts(res)
    inst = cov.pop("instron", None)
    if not cov:
        return ""
    parts = [f"{'Bayes' if m == 'bayes' else 'LS'}: {k}/{n}" for m, (k, n) in cov.items()]
    if inst is not None:
        parts.append(f"Bayes Instron-equivalent: {inst[0]}/{inst[1]}")
    return ("New-specimen 90 % interval covers the ground truth in " + ", ".join(parts)
            + " material × tip groups.")


def _paper_gt_text(materials: Sequence[str]) -> str:
    """The paper's own Instron ground truth of the given materials, e.g. 'White 111 kPa'."""
    from ..paper import PAPER_MATERIALS

    known = [f"{m} {PAPER_MATERIALS[m].E_pa * KPA:g} kPa" for m in materials
             if m in PAPER_MATERIALS]
    return ", ".join(known)


def summary_pages(res: ResultsFolder) -> list[Page]:
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
        if INSTRON_COL in table.columns:
            note += (" Instron-equiv.: with the specimen's footprint known, what a "
                     "compression test of a new specimen's block would read between the "
                     "run's platens (lubricated: E; bonded: c(nu)·E, c > 1; unknown: the "
                     "interval spans both), from the block's finite-element twin: the number "
                     "to set beside an Instron, like for like.")
        if HERTZ_COL in table.columns:
            note += (" Hertz LS: the paper's choice for a sphere — least squares with the "
                     "paraboloid (Hertz) law at the sphere's radius on the same traces, mean "
                     "over the traces, and its difference from the LS column (exact Sneddon "
                     "law).")
    else:
        note = ("No comparison.csv in this folder (run 'palpbayes compare'): per-group means "
                "± sd of the per-trace estimates.")
    cover = _coverage_line(res)
    chunks = page_chunks(len(table))
    per = max(c.stop - c.start for c in chunks)
    h = min(0.065, 1.0 / (per + 2.5))
    pages = []
    for k, sl in enumerate(chunks):
        part = table.iloc[sl]

        def build(fig: Figure, part: pd.DataFrame = part) -> None:
            top = 0.9
            if cover:
                fig.text(0.03, 0.905, cover, fontsize=10, fontweight="bold", va="bottom")
            # the note at the foot of the page, the table above it
            note_top = 0.05 + text_height([("t", note)], size=8, left=0.03, width=0.94)
            bottom = max(0.2, note_top + 0.02)
            ax = fig.add_axes((0.03, bottom, 0.94, top - bottom))
            draw_table(ax, part, fontsize=7.5 if part.shape[1] > 10 else 9.0, highlight=hl,
                       row_height=h * 0.7 / (top - bottom), wrap_header=12)
            text_lines(fig, [("t", note)], top=note_top, left=0.03, size=8, width=0.94)
        pages.append(Page(continued(title, k, len(chunks)), build, rows=len(part)))
    return pages


def comparison_pages(res: ResultsFolder) -> list[Page]:
    comp = res.comparison
    groups = comparison_groups(comp)
    split = material_pages(groups, CHART_GROUPS_PER_PAGE)
    cap = ("Thick bars: each method's 90 % interval of the material's modulus (least "
           "squares: t interval of the mean over traces; Bayes: pooled posterior with the "
           "budget). Thin bars: 90 % interval for a new specimen (least squares: t "
           "prediction interval; Bayes: posterior predictive). Grey bands: ground truth "
           "mean ± sd. Open diamonds: the paper's robot estimate ± sd (relative to the paper's "
           "own ground truth).")
    with_hertz = {law.kind for law in registered_laws() if law.hertz_approximation is not None}
    if any(t in with_hertz for _, t in groups) and "E_hertz_pa" in res.summary:
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
            text_lines(fig, [("t", ln) for ln in wrap(cap, 175)], top=0.11, left=0.07,
                        size=8)
        pages.append(Page(continued("Comparison per material and tip", k, len(split)),
                           build, rows=len(part)))
    return pages
